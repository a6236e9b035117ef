#!/bin/sh
# One side-by-side work-precision run of flexprr and its peers on a scene (default: the
# paper's scene at 20 Hz). Run from the repository root:
#   sh benches/peers/run_all.sh [scene.toml] [out_dir]
# Needs a Rust toolchain; the SciPy rows need python3 with numpy and scipy (skipped otherwise).
set -eu
scene=${1:-configs/paper_f20.toml}
out=${2:-out/work_precision}
mkdir -p "$out"
cargo build --release --bin flexprr
cargo build --release --manifest-path benches/peers/Cargo.toml
target_of() {
  cargo metadata --format-version 1 --no-deps "$@" \
    | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])'
}
peers_bin=$(target_of --manifest-path benches/peers/Cargo.toml)/release/flexprr-peers
flexprr_bin=$(target_of)/release/flexprr
# 1. The reference (rk45 at rtol 1e-14, checked with abm) and the ode_solvers rows.
"$peers_bin" "$scene" --out "$out/peers.csv" --write-reference "$out/reference.csv"
# 2. SciPy against the same reference (optional).
peer_files="--peers $out/peers.csv"
if python3 -c 'import scipy' 2>/dev/null; then
  python3 benches/peers/scipy_peers.py --reference "$out/reference.csv" --out "$out/scipy.csv"
  peer_files="$peer_files --peers $out/scipy.csv"
fi
# 3. flexprr's three integrators against the same reference; all rows merged.
# shellcheck disable=SC2086
"$flexprr_bin" work-precision "$scene" --out "$out" --reference "$out/reference.csv" $peer_files

#!/usr/bin/env bash
# Builds the flexprr wheel (maturin, abi3) into a fresh virtual environment and runs the
# Python tests. Exits non-zero when the build or a test fails, and when pytest collected no
# tests (its exit code 5).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
cd "$root"
python="${PYTHON:-python3}"
work="$root/target/python-ci"
rm -rf "$work"
mkdir -p "$work"
if ! "$python" -m venv "$work/venv" >/dev/null 2>&1; then
    # Debian splits venv out of the interpreter; install it (as root) and try again
    apt-get update >/dev/null && apt-get install -y python3-venv >/dev/null
    rm -rf "$work/venv"
    "$python" -m venv "$work/venv"
fi
venv_python="$work/venv/bin/python"
"$venv_python" -m pip install --quiet --upgrade pip
"$venv_python" -m pip install --quiet maturin numpy scipy pytest "dask[distributed]" control
cargo build --release --bin flexprr
"$work/venv/bin/maturin" build --release --manifest-path crates/python/Cargo.toml -o "$work/wheels"
"$venv_python" -m pip install --quiet "$work"/wheels/flexprr-*.whl
# run from outside the source tree, so that the installed wheel is what is imported
cd "$work"
status=0
FLEXPRR_BIN="$root/target/release/flexprr" "$venv_python" -m pytest "$root/tests/python" -q -p no:cacheprovider || status=$?
if [ "$status" -eq 5 ]; then
    echo "tests/python/run.sh: pytest collected no tests" >&2
    exit 1
fi
exit "$status"

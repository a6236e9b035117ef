#!/usr/bin/env bash
# Checks that a change leaves every product of the shipped scenes byte-identical: runs the
# same commands with the `flexprr` built from BASE (a git ref; default `main`) and from the
# working tree, then compares every file written and every line printed.
#
#   scripts/outputs-identical.sh [BASE]
#
# Only the measured wall time (`wall_time_s` and other `*wall*` keys) may differ. Exit 0 when
# everything else is identical, 1 with the list of differing files otherwise. Everything it
# writes goes under target/outputs-identical/.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
base_ref="${1:-main}"
work="$root/target/outputs-identical"
rm -rf "$work/base" "$work/head"
mkdir -p "$work"

# The base binary: its own worktree and target folder, kept between calls so that a second
# check only rebuilds what changed. FLEXPRR_BASE_BIN names a binary already built at BASE
# instead (several worktrees can then share one base build).
base_bin="${FLEXPRR_BASE_BIN:-}"
if [ -z "$base_bin" ]; then
    base_tree="$work/base-tree"
    if [ -d "$base_tree" ]; then
        git -C "$base_tree" checkout -q --detach "$base_ref"
    else
        git worktree add -q --detach "$base_tree" "$base_ref"
    fi
    echo "building flexprr at $base_ref ($(git -C "$base_tree" rev-parse --short HEAD))" >&2
    CARGO_TARGET_DIR="$work/base-target" cargo build -q --release --bin flexprr \
        --manifest-path "$base_tree/Cargo.toml"
    base_bin="$work/base-target/release/flexprr"
else
    echo "using the base binary named by FLEXPRR_BASE_BIN" >&2
fi
echo "building flexprr from the working tree" >&2
cargo build -q --release --bin flexprr

# Runs every product command with the binary $1 into the folder $2; each command's standard
# output, standard error and exit code go to $2/<name>.log.
products() {
    local bin="$1" out="$2" scene name
    mkdir -p "$out"
    record() {
        local name="$1"
        shift
        local status=0
        "$@" >"$out/$name.log" 2>&1 || status=$?
        echo "exit $status" >>"$out/$name.log"
    }
    for scene in configs/*.toml configs/stress/*.toml; do
        name="$(basename "$scene" .toml)"
        case "$name" in study_* | link_paper | modal_test) continue ;; esac
        # A scene newer than the base binary (a [plan] table, a key of a later feature) is
        # refused by the base's `check` and accepted by this binary's: it is skipped, said
        # on standard error. A scene both refuse is compared like every other (its errors).
        if ! "$base_bin" check "$scene" >/dev/null 2>&1 && "$root/target/release/flexprr" check "$scene" >/dev/null 2>&1; then
            echo "skipping $name: the base binary refuses it (newer than the base)" >&2
            continue
        fi
        record "run_$name" "$bin" run "$scene" --out "$out/run_$name" --quiet
    done
    record check_paper "$bin" check configs/paper_f20.toml
    record kinematics "$bin" kinematics configs/paper_f20.toml --out "$out/kinematics.csv"
    record beam "$bin" beam configs/link_paper.toml --json
    record modes_servo "$bin" modes configs/servo_f20.toml --pose -0.1,0,45 --out "$out/modes_servo"
    record modes_coupled_time "$bin" modes configs/coupled_f20.toml --time 0.02 --json
    record modes_motor "$bin" modes configs/servo_motor_f2.toml --out "$out/modes_motor"
    record frf_modal_test "$bin" frf --config configs/modal_test.toml --out "$out/frf_modal_test"
    record frf_servo "$bin" frf configs/servo_f20.toml --input slider_force:1 --output slider:1 \
        --output deflection:1@0.5 --out "$out/frf_servo"
    record statespace_servo "$bin" statespace configs/servo_f20.toml --input slider_force:1 \
        --output slider:1 --output platform:x --out "$out/statespace_servo"
    record study_speed_limit "$bin" study configs/study_speed_limit.toml \
        --out "$out/study_speed_limit" --threads 2 --quiet
    record study_thickness_payload "$bin" study configs/study_thickness_payload.toml \
        --out "$out/study_thickness_payload" --threads 2 --quiet
    record study_frequency_map "$bin" study configs/study_frequency_map.toml \
        --out "$out/study_frequency_map" --threads 2 --quiet
}

echo "running the products of $base_ref" >&2
products "$base_bin" "$work/base"
echo "running the products of the working tree" >&2
products "$root/target/release/flexprr" "$work/head"

# Compares two trees, ignoring measured times (JSON keys naming a wall time or a timing, the
# durations printed in logs), the output folders' own names and the order of printed lines.
python3 - "$work/base" "$work/head" <<'PY'
import os, re, sys
base, head = sys.argv[1], sys.argv[2]
measured = [
    (re.compile(rb'"[a-z_]*wall[a-z_]*"\s*:\s*[-0-9.eE+]+'), b'"wall": 0'),
    (re.compile(rb'"timing_s"\s*:\s*\{[^}]*\}'), b'"timing_s": {}'),
    (re.compile(rb'[0-9][0-9.]* ?(ms|s)\b'), b'TIME'),
]
def files(top):
    found = set()
    for folder, _, names in os.walk(top):
        for name in names:
            found.add(os.path.relpath(os.path.join(folder, name), top))
    return found
def text(path, top):
    data = open(path, 'rb').read().replace(top.encode(), b'OUT')
    if path.endswith('.json'):
        for pattern, replacement in measured[:2]:
            data = pattern.sub(replacement, data)
    if path.endswith('.log'):
        for pattern, replacement in measured:
            data = pattern.sub(replacement, data)
        # a study's cases finish in any order on several threads
        data = b'\n'.join(sorted(data.split(b'\n')))
    return data
a, b = files(base), files(head)
problems = [f'only in base: {f}' for f in sorted(a - b)] + [f'only in head: {f}' for f in sorted(b - a)]
for f in sorted(a & b):
    if text(os.path.join(base, f), base) != text(os.path.join(head, f), head):
        problems.append(f'differs: {f}')
for p in problems:
    print(p)
print(f'{len(a & b)} files compared, {len(problems)} differences', file=sys.stderr)
sys.exit(1 if problems else 0)
PY

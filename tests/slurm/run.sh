#!/usr/bin/env bash
# End-to-end test of the Slurm path of `flexprr study` (docs/studies.md, "Slurm").
#
# Starts a throw-away single-node Slurm cluster (munged, slurmctld and slurmd on 127.0.0.1,
# 2 CPUs, no accounting, no cgroups) whose files all live in one temporary directory, then:
#   1. runs tests/slurm/study.toml once on this machine without Slurm (the reference table);
#   2. submits configs/slurm_study.sbatch as a job array of 3 tasks and the merge as a job
#      that depends on it (afterany), and checks that the merged results.csv is
#      byte-identical to the reference;
#   3. submits the array again and cancels tasks 2 and 3 once each has recorded a case;
#      checks that the merge fails (exit 1) naming both incomplete shards, and that a job
#      depending afterok on the array stays pending for good; requeues task 2 in place
#      (scontrol requeue) and submits index 3 again alone; both resume; merges again and
#      checks the table again;
#   4. prints the measured figures: cases per second per task and the scheduler overhead.
# Every daemon it started is stopped by PID, and the temporary directory is removed, on
# success and on failure.
#
# Usage: bash tests/slurm/run.sh          (as root; installs slurm-wlm and munge if missing)
# Environment: FLEXPRR (binary, default target/release/flexprr, built if missing),
#   SLURM_TEST_TIMEOUT (seconds to wait for any one job, default 300),
#   SLURM_TEST_KEEP=1 (keep the temporary directory for inspection).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
STUDY=$ROOT/tests/slurm/study.toml
SBATCH_SCRIPT=$ROOT/configs/slurm_study.sbatch
TIMEOUT=${SLURM_TEST_TIMEOUT:-300}
SHARDS=3

say() { printf 'slurm test: %s\n' "$*"; }
die() {
    printf 'slurm test: FAILED: %s\n' "$*" >&2
    exit 1
}
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }

# --- Slurm and munge -----------------------------------------------------------------------
[ "$(id -u)" -eq 0 ] || die "must run as root (slurmd starts jobs as their user, and Slurm and munge may need installing)"
missing=()
for tool in munged mungekey slurmctld slurmd sbatch squeue scontrol scancel; do
    command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
done
if [ ${#missing[@]} -gt 0 ]; then
    say "installing slurm-wlm and munge (missing: ${missing[*]})"
    export DEBIAN_FRONTEND=noninteractive
    apt-get -o DPkg::Lock::Timeout=600 update -qq
    apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi

# --- the binary ----------------------------------------------------------------------------
FLEXPRR=${FLEXPRR:-$ROOT/target/release/flexprr}
if [ ! -x "$FLEXPRR" ]; then
    say "building $FLEXPRR"
    (cd "$ROOT" && cargo build --release --bin flexprr)
fi
[ -x "$FLEXPRR" ] || die "no flexprr binary at $FLEXPRR"
export FLEXPRR

# --- temporary directory and cleanup -------------------------------------------------------
TMP=$(mktemp -d "${TMPDIR:-/tmp}/flexprr-slurm.XXXXXX")
DAEMON_PIDS=()   # started daemons, in start order
# Submitted job ids go to the file $TMP/jobs, one a line ($(submit ...) runs in a subshell).

cleanup() {
    local rc=$?
    trap - EXIT INT TERM
    set +e
    local jobs ids=()
    [ -f "$TMP/jobs" ] && mapfile -t ids <"$TMP/jobs"
    jobs=$(IFS=,; echo "${ids[*]}")
    if [ -n "$jobs" ] && [ -n "${SLURM_CONF:-}" ]; then
        scancel "${ids[@]}" 2>/dev/null
        # Let slurmd end the job steps before it is stopped.
        for _ in $(seq 1 100); do
            [ -z "$(squeue -h -j "$jobs" -o %i 2>/dev/null)" ] && break
            sleep 0.2
        done
    fi
    if [ "$rc" -ne 0 ] && [ -d "$TMP" ]; then
        for log in "$TMP"/*.log "$TMP"/*.stderr "$TMP"/work/*.out; do
            [ -f "$log" ] || continue
            printf '\n--- last lines of %s ---\n' "$(basename "$log")" >&2
            tail -n 15 "$log" >&2
        done
    fi
    local i
    for ((i = ${#DAEMON_PIDS[@]} - 1; i >= 0; i--)); do
        kill "${DAEMON_PIDS[i]}" 2>/dev/null
    done
    for ((i = ${#DAEMON_PIDS[@]} - 1; i >= 0; i--)); do
        for _ in $(seq 1 50); do
            kill -0 "${DAEMON_PIDS[i]}" 2>/dev/null || break
            sleep 0.1
        done
        kill -KILL "${DAEMON_PIDS[i]}" 2>/dev/null
        wait "${DAEMON_PIDS[i]}" 2>/dev/null
    done
    if [ "${SLURM_TEST_KEEP:-0}" = 1 ]; then
        say "kept $TMP"
    else
        rm -rf "$TMP"
    fi
    if [ "$rc" -eq 0 ]; then say "passed"; else say "failed (exit $rc)" >&2; fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# A TCP port on 127.0.0.1 that nothing listens on, from $1 upwards.
free_port() {
    local p
    for ((p = $1; p < $1 + 200; p++)); do
        if ! (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then
            echo "$p"
            return
        fi
    done
    die "no free port in $1..$(($1 + 199))"
}

# --- munged --------------------------------------------------------------------------------
# munged wants every directory above its socket searchable by all, and its key private.
chmod 711 "$TMP"
mkdir -m 755 "$TMP/munge"
mkdir -m 700 "$TMP/munge-key"
mungekey --create --keyfile="$TMP/munge-key/munge.key"
munged --foreground --force --key-file="$TMP/munge-key/munge.key" \
    --socket="$TMP/munge/socket" --pid-file="$TMP/munge/munged.pid" \
    --seed-file="$TMP/munge-key/seed" --log-file="$TMP/munged.log" >"$TMP/munged.stderr" 2>&1 &
DAEMON_PIDS+=($!)
for _ in $(seq 1 100); do
    [ -S "$TMP/munge/socket" ] && break
    kill -0 "${DAEMON_PIDS[-1]}" 2>/dev/null || die "munged exited at start"
    sleep 0.1
done
[ -S "$TMP/munge/socket" ] || die "munged did not create its socket within 10 s"

# --- slurm.conf ----------------------------------------------------------------------------
NODE=$(hostname -s)
CTLD_PORT=$(free_port 16817)
SLURMD_PORT=$(free_port $((CTLD_PORT + 1)))
MEM_MB=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 / 2 }' /proc/meminfo)
mkdir -p "$TMP/state" "$TMP/spool" "$TMP/work"
: >"$TMP/plugstack.conf"
cat >"$TMP/slurm.conf" <<EOF
# Single-node test cluster written by tests/slurm/run.sh.
ClusterName=flexprrtest
SlurmctldHost=$NODE(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$TMP/munge/socket
CredType=cred/munge
StateSaveLocation=$TMP/state
SlurmdSpoolDir=$TMP/spool
SlurmctldPidFile=$TMP/slurmctld.pid
SlurmdPidFile=$TMP/slurmd.pid
SlurmctldLogFile=$TMP/slurmctld.log
SlurmdLogFile=$TMP/slurmd.log
PlugStackConfig=$TMP/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
MinJobAge=600
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=2 RealMemory=$MEM_MB State=UNKNOWN
PartitionName=test Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$TMP/slurm.conf

slurmctld -D -c -f "$SLURM_CONF" >"$TMP/slurmctld.stderr" 2>&1 &
DAEMON_PIDS+=($!)
slurmd -D -N "$NODE" -f "$SLURM_CONF" >"$TMP/slurmd.stderr" 2>&1 &
DAEMON_PIDS+=($!)
for _ in $(seq 1 300); do
    state=$(sinfo -h -n "$NODE" -o %t 2>/dev/null || true)
    [ "$state" = idle ] && break
    for pid in "${DAEMON_PIDS[@]}"; do
        kill -0 "$pid" 2>/dev/null || die "a Slurm daemon (PID $pid) exited at start"
    done
    sleep 0.1
done
[ "$state" = idle ] || die "node $NODE not idle within 30 s (state: '${state:-none}')"
say "cluster up: node $NODE, slurmctld on port $CTLD_PORT, slurmd on $SLURMD_PORT"

# --- job helpers ---------------------------------------------------------------------------
# One line "<jobid> <state> <exit code>" per job or array task of job $1, from slurmctld.
job_states() {
    scontrol -o show job "$1" 2>/dev/null | awk '{
        id = ""; st = ""; ex = ""
        for (i = 1; i <= NF; i++) {
            if ($i ~ /^JobId=/) id = substr($i, 7)
            if ($i ~ /^ArrayJobId=/) aj = substr($i, 12)
            if ($i ~ /^ArrayTaskId=/) id = aj "_" substr($i, 13)
            if ($i ~ /^JobState=/) st = substr($i, 10)
            if ($i ~ /^ExitCode=/) ex = substr($i, 10)
        }
        print id, st, ex
    }'
}

# Waits until every task of job $1 has ended; fails after $TIMEOUT seconds.
wait_job() {
    local deadline states
    deadline=$(($(date +%s) + TIMEOUT))
    while :; do
        states=$(job_states "$1")
        [ -n "$states" ] || die "job $1 is unknown to slurmctld"
        if ! grep -qE ' (PENDING|RUNNING|CONFIGURING|COMPLETING|REQUEUED|RESIZING|SUSPENDED) ' <<<"$states"; then
            return 0
        fi
        if [ "$(date +%s)" -ge "$deadline" ]; then
            die "job $1 not finished after ${TIMEOUT} s: $(tr '\n' ';' <<<"$states")"
        fi
        sleep 0.2
    done
}

# Checks that every task of job $1 ended COMPLETED with exit code 0.
expect_completed() {
    local bad
    bad=$(job_states "$1" | awk '$2 != "COMPLETED" || $3 != "0:0"')
    [ -z "$bad" ] || die "job $1 did not complete cleanly: $bad"
}

submit() {
    local id
    id=$(sbatch --parsable "$@") || die "sbatch $* failed"
    id=${id%%;*}
    echo "$id" >>"$TMP/jobs"
    echo "$id"
}

# --- 1. the reference: one machine, no Slurm -------------------------------------------------
cd "$TMP/work"
t0=$(now)
"$FLEXPRR" study "$STUDY" --out single --quiet >single.log
t1=$(now)
CASES=$(($(wc -l <single/results.csv) - 1))
say "single-machine run: $CASES cases in $(elapsed "$t0" "$t1") s on 2 threads"

# --- 2. the job array and a dependent merge ------------------------------------------------
t0=$(now)
ARRAY=$(submit --array=1-$SHARDS --cpus-per-task=1 --mem-per-cpu=200M --time=10:00 \
    --output='%x-%A_%a.out' "$SBATCH_SCRIPT" "$STUDY" happy)
MERGE=$(submit --dependency=afterany:"$ARRAY" --cpus-per-task=1 --mem-per-cpu=200M --time=5:00 \
    --job-name=flexprr-merge --output='merge-%j.out' \
    --wrap "\"\$FLEXPRR\" merge happy/shard-* --out happy/merged")
say "submitted array job $ARRAY (tasks 1-$SHARDS) and merge job $MERGE (afterany:$ARRAY)"
wait_job "$MERGE"
t1=$(now)
expect_completed "$ARRAY"
expect_completed "$MERGE"
cmp happy/merged/results.csv single/results.csv ||
    die "the merged table of the job array differs from the single-machine table"
say "merged table of 3 array tasks is byte-identical to the single-machine table"
WALL=$(elapsed "$t0" "$t1")

# Per-task timings from the lines the job script prints.
task_lines=$(cat flexprr-study-"$ARRAY"_*.out | grep '^flexprr-study: ' || true)
[ "$(grep -c . <<<"$task_lines")" -eq "$SHARDS" ] || die "expected $SHARDS timing lines, got: $task_lines"

# --- 3. cancel tasks 2 and 3 midway, merge (refused), requeue and resubmit them, merge -------
# Cases of shard k of $SHARDS.
shard_size() {
    awk -v n="$SHARDS" -v c="$CASES" -v k="$1" 'BEGIN { m = 0; for (i = 0; i < c; i++) if (i % n == k - 1) m++; print m }'
}
recorded() { find "$1/cases" -name '*.json' 2>/dev/null | wc -l; }

# Cancels task $2 of array job $1 as soon as its shard directory $3 holds a case record,
# that is while it runs: the shard's cases run in id order on one thread, and the study puts
# seconds of integrated cases after the frequencies-only ones.
cancel_midway() {
    local deadline state
    deadline=$(($(date +%s) + TIMEOUT))
    until compgen -G "$3/cases/*.json" >/dev/null; do
        [ "$(date +%s)" -lt "$deadline" ] || die "task $1_$2 recorded no case within ${TIMEOUT} s"
        sleep 0.02
    done
    scancel "$1_$2"
    while :; do
        state=$(job_states "$1_$2" | awk '{ print $2 }')
        case $state in
        CANCELLED) break ;;
        RUNNING | COMPLETING) sleep 0.1 ;;
        *) die "task $1_$2 ended $state, not CANCELLED: it finished before the cancel reached it" ;;
        esac
        [ "$(date +%s)" -lt "$deadline" ] || die "task $1_$2 still $state ${TIMEOUT} s after scancel"
    done
    local have
    have=$(recorded "$3")
    if [ "$have" -lt 1 ] || [ "$have" -ge "$(shard_size "$2")" ]; then
        die "cancelled task $1_$2 holds $have of its $(shard_size "$2") cases; expected some but not all"
    fi
    [ ! -e "$3/results.csv" ] || die "cancelled task $1_$2 wrote a table"
}

CUT=$(submit --array=1-$SHARDS --cpus-per-task=1 --mem-per-cpu=200M --time=10:00 \
    --output='%x-%A_%a.out' "$SBATCH_SCRIPT" "$STUDY" cut)
# The merge as the recipe submits it (afterany), and an afterok job that a cancelled task
# leaves pending for good.
REFUSED=$(submit --dependency=afterany:"$CUT" --cpus-per-task=1 --time=5:00 \
    --job-name=flexprr-merge --output='refused-%j.out' \
    --wrap "\"\$FLEXPRR\" merge cut/shard-* --out cut/merged")
STALE=$(submit --dependency=afterok:"$CUT" --time=1:00 --output=/dev/null --wrap true)
cancel_midway "$CUT" 2 cut/shard-2
cancel_midway "$CUT" 3 cut/shard-3
cut2=$(recorded cut/shard-2)
cut3=$(recorded cut/shard-3)
say "cancelled tasks ${CUT}_2 and ${CUT}_3 after $cut2 of $(shard_size 2) and $cut3 of $(shard_size 3) cases"
wait_job "$CUT"
[ "$(job_states "${CUT}_1" | awk '{ print $2, $3 }')" = "COMPLETED 0:0" ] || die "task ${CUT}_1 did not complete"

# The merge refuses the incomplete shards and says which, with their counts.
wait_job "$REFUSED"
refused=$(job_states "$REFUSED")
[ "$(awk '{ print $2, $3 }' <<<"$refused")" = "FAILED 1:0" ] ||
    die "merge of an incomplete study should fail with exit code 1: $refused"
for expect in "shard 2/3 (cut/shard-2) has $cut2 of its $(shard_size 2) cases" \
    "shard 3/3 (cut/shard-3) has $cut3 of its $(shard_size 3) cases"; do
    grep -qF "$expect" "refused-$REFUSED.out" ||
        die "the refused merge does not say \"$expect\": $(cat "refused-$REFUSED.out")"
done
[ ! -e cut/merged/results.csv ] || die "the refused merge wrote a table"
say "merge with afterany ran and refused: $(cat "refused-$REFUSED.out")"

deadline=$(($(date +%s) + TIMEOUT))
until [ "$(squeue -h -j "$STALE" -o %r)" = DependencyNeverSatisfied ]; do
    [ "$(date +%s)" -lt "$deadline" ] || die "afterok job $STALE: $(squeue -h -j "$STALE" -o '%T %r')"
    sleep 0.2
done
scancel "$STALE"
say "a job with afterok on the array stays PENDING (DependencyNeverSatisfied)"

# Task 2 requeued in place, task 3 submitted again alone (so with the shard count): both
# resume their shard. Slurm holds a requeued job for about two minutes (reason BeginTime);
# setting its start time to now releases it.
scontrol requeue "${CUT}_2"
scontrol update JobId="${CUT}_2" StartTime=now
AGAIN=$(submit --array=3 --cpus-per-task=1 --mem-per-cpu=200M --time=10:00 \
    --output='%x-%A_%a.out' "$SBATCH_SCRIPT" "$STUDY" cut "$SHARDS")
wait_job "$CUT"
wait_job "$AGAIN"
expect_completed "${CUT}_2"
expect_completed "$AGAIN"
grep -qF "($(($(shard_size 2) - cut2)) run now, $cut2 resumed)" "flexprr-study-${CUT}_2.out" ||
    die "the requeued task did not resume its $cut2 cases: $(cat "flexprr-study-${CUT}_2.out")"
grep -qF "($(($(shard_size 3) - cut3)) run now, $cut3 resumed)" "flexprr-study-${AGAIN}_3.out" ||
    die "the resubmitted task did not resume its $cut3 cases: $(cat "flexprr-study-${AGAIN}_3.out")"
MERGE2=$(submit --cpus-per-task=1 --time=5:00 --job-name=flexprr-merge --output='merge-%j.out' \
    --wrap "\"\$FLEXPRR\" merge cut/shard-* --out cut/merged")
wait_job "$MERGE2"
expect_completed "$MERGE2"
cmp cut/merged/results.csv single/results.csv ||
    die "after cancel and resume, the merged table differs from the single-machine table"
say "requeued task ${CUT}_2 and resubmitted task ${AGAIN}_3 resumed; merged table is byte-identical again"

# --- 4. figures ----------------------------------------------------------------------------
# Seconds since the epoch of a Slurm time stamp (1 s resolution).
epoch() { date -d "$1" +%s; }
# Field $2 (SubmitTime, StartTime, EndTime) of every task of job $1, as seconds.
job_times() {
    scontrol -o show job "$1" | tr ' ' '\n' | sed -n "s/^$2=//p" | while read -r t; do epoch "$t"; done
}
say "figures (tasks of array job $ARRAY, 1 CPU each, 2 CPUs on the node):"
k=0
while read -r line; do
    k=$((k + 1))
    shard=$(sed -n 's/^flexprr-study: shard \([0-9]*\)\/.*/\1/p' <<<"$line")
    secs=$(sed -n 's/.* after \([0-9.]*\) s$/\1/p' <<<"$line")
    n=$(awk -v n="$SHARDS" -v c="$CASES" -v k="$shard" 'BEGIN { m = 0; for (i = 0; i < c; i++) if (i % n == k - 1) m++; print m }')
    awk -v k="$shard" -v n="$SHARDS" -v m="$n" -v s="$secs" \
        'BEGIN { printf "    task %s/%s: %d cases in %.3f s, %.1f cases/s\n", k, n, m, s, m / s }'
done <<<"$task_lines"
submitted=$(job_times "$ARRAY" SubmitTime | sort -n | head -1)
first_start=$(job_times "$ARRAY" StartTime | sort -n | head -1)
last_end=$(job_times "$ARRAY" EndTime | sort -n | tail -1)
merge_start=$(job_times "$MERGE" StartTime)
merge_end=$(job_times "$MERGE" EndTime)
# The shortest time the tasks' own run times allow: Slurm starts the tasks in index order, each
# on the first of the node's 2 CPUs that is free.
critical=$(sort -t/ -k1,1n <<<"$task_lines" | awk '{ for (i = 1; i <= NF; i++) if ($i == "after") t = $(i + 1)
    c = (a <= b) ? a : b; if (a <= b) a = c + t; else b = c + t }
    END { printf "%.2f", (a > b) ? a : b }')
overhead=$(awk -v w="$WALL" -v c="$critical" 'BEGIN { printf "%.2f", w - c }')
say "    submission to merged table: $WALL s; the task run times alone need $critical s on 2 CPUs, so Slurm (and the merge) added $overhead s"
t0=$(now)
EMPTY=$(submit --time=1:00 --output=/dev/null --wrap true)
wait_job "$EMPTY"
say "    an empty job (--wrap true), sbatch to COMPLETED: $(elapsed "$t0" "$(now)") s"
say "    submission to first task start: $((first_start - submitted)) s; last task end to merge start: $((merge_start - last_end)) s; merge: $((merge_end - merge_start)) s (Slurm times, 1 s resolution)"

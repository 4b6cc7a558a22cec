#!/usr/bin/env bash
# End-to-end test of the cluster workflow on a real Slurm (run by .ci/run, as root):
# starts a single-node test cluster (scripts/slurm_test_cluster.sh), submits
# experiments/ci/slurm_small.toml through scripts/slurm_array.sh as 3 array tasks plus
# the merge job, cancels task 1 with scancel between two of its cells and reruns it
# with --tasks 1, and checks:
#   - the merged results.jsonl equals a single-machine run of the same file, row for
#     row, once the machine-dependent `cost` objects are removed;
#   - the cancelled task kept its finished cells, the rerun redid none of them (their
#     rows are unchanged, cost included) and no key appears twice;
#   - the report was written by exactly one merge job;
#   - Slurm's view: the task with the failed cell FAILED (exit 1), the others COMPLETED,
#     the cancelled one CANCELLED; job names, --time, --mem and the %2 throttle.
# The cluster is stopped (every daemon and job process killed) whatever happens; every
# wait is bounded. KEEP=1 keeps the work directory (printed) for a look afterwards.
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
export RB_SLURM_DIR="${RB_SLURM_DIR:-/tmp/reconbench-slurm-e2e}"
CLUSTER="$ROOT/scripts/slurm_test_cluster.sh"
EXP="$ROOT/experiments/ci/slurm_small.toml"
N=3
CELLS=16
WORK="$(mktemp -d /tmp/rb-slurm-e2e.XXXXXX)"
OUT="$WORK/cluster"
T0=$SECONDS

say() { echo "slurm_e2e: $*"; }
fail() {
    echo "slurm_e2e: FAIL: $*" >&2
    exit 1
}

cleanup() {
    local rc=$?
    trap - EXIT INT TERM
    if ((rc != 0)); then
        echo "slurm_e2e: failed (exit $rc); job logs and cluster log tails:" >&2
        for f in "$OUT"/slurm/*.out; do
            [[ -f $f ]] && { echo "--- $f" >&2; tail -n 20 "$f" >&2; }
        done
        tail -n 20 "$RB_SLURM_DIR/log/slurmctld.log" "$RB_SLURM_DIR/log/slurmd.log" >&2 2>/dev/null || true
    fi
    [[ -n ${SINGLE_PID:-} ]] && kill "$SINGLE_PID" 2>/dev/null
    "$CLUSTER" stop || true
    if [[ ${KEEP:-0} == 1 ]]; then
        echo "slurm_e2e: kept $WORK" >&2
    else
        rm -rf "$WORK"
    fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# Waits up to $1 seconds for the command "${@:3}" to succeed; $2 says what for.
wait_for() {
    local limit="$1" what="$2" t0=$SECONDS
    shift 2
    until "$@"; do
        ((SECONDS - t0 < limit)) || fail "timed out after ${limit}s waiting for $what"
        sleep 0.2
    done
}

rows_in() { if [[ -f $1 ]]; then wc -l <"$1" | tr -d ' '; else echo 0; fi; }

# One field of `scontrol show job` for a job or array task (e.g. JobState).
job_field() {
    timeout 10 scontrol -o show job "$1" 2>/dev/null |
        head -n 1 | tr ' ' '\n' | sed -n "s/^$2=//p"
}

job_done() {
    case "$(job_field "$1" JobState)" in
    COMPLETED | FAILED | CANCELLED | TIMEOUT | OUT_OF_MEMORY | NODE_FAIL) return 0 ;;
    *) return 1 ;;
    esac
}

shard_file() { echo "$OUT/results.shard-$1-of-$N.jsonl"; }
shard_has() { (($(rows_in "$(shard_file "$1")") >= $2)); }

# --- Slurm itself: installed here if missing. A machine that cannot install it (no
# apt-get, not root, no reachable package registry) skips this test with a notice,
# unless RB_SLURM_REQUIRED=1; once Slurm is installed every failure below fails.
if ! "$CLUSTER" install; then
    if [[ ${RB_SLURM_REQUIRED:-0} == 1 ]]; then
        fail "Slurm could not be installed (see above)"
    fi
    say "SKIPPED: Slurm is not installed and could not be installed here (see above);"
    say "set RB_SLURM_REQUIRED=1 to make this a failure"
    trap - EXIT
    exit 0
fi

# --- the binary: the debug build the tests already made, else build it
BIN="${RECONBENCH:-${CARGO_TARGET_DIR:-$ROOT/target}/debug/reconbench}"
if [[ ! -x $BIN ]]; then
    say "building target/debug/reconbench"
    (cd "$ROOT" && cargo build --locked -q -p reconbench-cli)
fi
export RECONBENCH="$BIN"

# --- the cluster
"$CLUSTER" start
eval "$("$CLUSTER" env)"
say "cluster up after $((SECONDS - T0)) s"

# --- the single-machine reference, run beside the cluster jobs (its costs differ anyway)
"$BIN" run "$EXP" --out "$WORK/single" -j 2 --no-report >"$WORK/single.log" 2>&1 &
SINGLE_PID=$!

# --- the array (3 tasks, 1 CPU each, at most 2 at once) and its merge job
read -r ARRAY MERGE < <(OUT="$OUT" "$ROOT/scripts/slurm_array.sh" --parsable --throttle 2 "$EXP" "$N" 1)
[[ $ARRAY =~ ^[0-9]+$ && $MERGE =~ ^[0-9]+$ ]] || fail "slurm_array.sh gave no job ids"
say "array job $ARRAY, merge job $MERGE"

[[ "$(job_field "$ARRAY" JobName)" == rb-slurm_small-shard ]] || fail "array job name: $(job_field "$ARRAY" JobName)"
[[ "$(job_field "$MERGE" JobName)" == rb-slurm_small-merge ]] || fail "merge job name: $(job_field "$MERGE" JobName)"
[[ "$(job_field "$ARRAY" ArrayTaskThrottle)" == 2 ]] || fail "throttle: $(job_field "$ARRAY" ArrayTaskThrottle)"
# 6 cells per task x 20 s timeout x 1.1 + 5 min = 432 s -> 8 min; 512 MiB x 1 CPU + 512.
[[ "$(job_field "$ARRAY" TimeLimit)" == 00:08:00 ]] || fail "time limit: $(job_field "$ARRAY" TimeLimit)"
[[ "$(job_field "$ARRAY" MinMemoryNode)" == 1G ]] || fail "memory: $(job_field "$ARRAY" MinMemoryNode)"
[[ "$(job_field "$MERGE" Dependency)" == "afterany:${ARRAY}_*"* ]] || fail "merge dependency: $(job_field "$MERGE" Dependency)"

# --- cancel task 1 once two of its five cells are done
wait_for 120 "task 1 to finish two cells" shard_has 1 2
timeout 10 scancel "${ARRAY}_1"
wait_for 60 "task 1 to be cancelled" job_done "${ARRAY}_1"
[[ "$(job_field "${ARRAY}_1" JobState)" == CANCELLED ]] || fail "task 1: $(job_field "${ARRAY}_1" JobState)"
cp "$(shard_file 1)" "$WORK/at_cancel.jsonl"
KEPT=$(rows_in "$WORK/at_cancel.jsonl")
((KEPT >= 2 && KEPT < 5)) || fail "task 1 had $KEPT of 5 rows when cancelled (not mid-run)"
say "task 1 cancelled with $KEPT of 5 cells done"

# --- rerun task 1 (its own merge job follows)
read -r ARRAY2 MERGE2 < <(OUT="$OUT" "$ROOT/scripts/slurm_array.sh" --parsable --throttle 2 --tasks 1 "$EXP" "$N" 1)
[[ $ARRAY2 =~ ^[0-9]+$ && $MERGE2 =~ ^[0-9]+$ ]] || fail "slurm_array.sh --tasks 1 gave no job ids"
say "rerun: array job $ARRAY2, merge job $MERGE2"

for j in "${ARRAY}_0" "${ARRAY}_2" "${ARRAY2}_1" "$MERGE" "$MERGE2"; do
    wait_for 180 "job $j to end" job_done "$j"
done
wait_for 60 "the single-machine run" bash -c "! kill -0 $SINGLE_PID 2>/dev/null"
wait "$SINGLE_PID" || fail "the single-machine run failed: $(tail -n 5 "$WORK/single.log")"
SINGLE_PID=""
say "all jobs ended after $((SECONDS - T0)) s"

# --- rows: the rerun kept the cancelled task's rows, nothing twice, equal to one machine
python3 - "$WORK/single/results.jsonl" "$OUT/results.jsonl" "$WORK/at_cancel.jsonl" "$(shard_file 1)" "$CELLS" <<'EOF'
import json, sys

single, merged, at_cancel, shard1, cells = sys.argv[1:]

def rows(path):
    with open(path) as f:
        return [json.loads(line) for line in f if line.endswith("\n")]

def without_cost(row):
    return json.dumps({k: v for k, v in row.items() if k != "cost"}, sort_keys=False)

def fail(msg):
    sys.exit(f"slurm_e2e: FAIL: {msg}")

s, m = rows(single), rows(merged)
keys = [r["key"] for r in m]
if len(set(keys)) != len(keys):
    fail(f"merged results hold a key twice ({len(keys)} rows, {len(set(keys))} keys)")
if len(m) != int(cells) or len(s) != int(cells):
    fail(f"{len(m)} merged and {len(s)} single-machine rows, want {cells}")
kept, final = rows(at_cancel), rows(shard1)
bad = [(r["key"], r["error"]) for r in kept if r["status"] != "ok"]
if bad:
    fail(f"the cancelled task recorded failed rows for cells it was running: {bad}")
for a, b in zip(s, m):
    if without_cost(a) != without_cost(b):
        diff = [k for k in a if k != "cost" and a.get(k) != b.get(k)]
        fail(f"row {a['key']} differs from the single-machine run in {diff}")
for r in kept:
    if r not in final:
        fail(f"the rerun rewrote the finished cell {r['key']} (or lost it)")
print(f"slurm_e2e: {len(m)} merged rows equal the single-machine run apart from cost; "
      f"{len(kept)} rows kept across the cancel")
EOF

# --- Slurm's states: FAILED exactly for the task whose shard has a failed cell
state_of_shard() {
    local job="$1" shard="$2" want=COMPLETED code=0:0
    if grep -qv '"status":"ok"' "$(shard_file "$shard")"; then
        want=FAILED
        code=1:0
    fi
    [[ "$(job_field "$job" JobState)" == "$want" && "$(job_field "$job" ExitCode)" == "$code" ]] ||
        fail "job $job (shard $shard): $(job_field "$job" JobState) exit $(job_field "$job" ExitCode), want $want $code"
    echo "$want"
}
S0=$(state_of_shard "${ARRAY}_0" 0)
S1=$(state_of_shard "${ARRAY2}_1" 1)
S2=$(state_of_shard "${ARRAY}_2" 2)
[[ "$S0 $S1 $S2" == "FAILED COMPLETED COMPLETED" ]] || fail "task states $S0 $S1 $S2: the failed cell is in shard 0"
say "task states: 0 $S0, 1 CANCELLED then $S1, 2 $S2"

# --- per-shard logs
for f in "shard-0-of-3.$ARRAY" "shard-1-of-3.$ARRAY" "shard-2-of-3.$ARRAY" "shard-1-of-3.$ARRAY2" \
    "merge.$MERGE" "merge.$MERGE2"; do
    [[ -s $OUT/slurm/$f.out ]] || fail "no log $OUT/slurm/$f.out"
done

# --- the report, written once
WROTE=$(cat "$OUT"/slurm/merge.*.out | grep -c '^rb-merge: wrote the report' || true)
((WROTE == 1)) || fail "$WROTE merge jobs wrote the report, want 1"
[[ -s $OUT/report.md ]] || fail "no report.md"

say "PASS in $((SECONDS - T0)) s"

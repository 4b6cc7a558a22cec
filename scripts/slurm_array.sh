#!/usr/bin/env bash
# Run a reconbench experiment as a Slurm job array: task i runs shard i/N of the grid,
# writing <out>/results.shard-i-of-N.jsonl; a dependent job merges the shards and writes
# the report once every shard is complete.
#
#   scripts/slurm_array.sh experiments/quickstart.toml 16              # 16 tasks + merge
#   scripts/slurm_array.sh --throttle 8 exp.toml 64 4                  # 8 at a time, 4 CPUs each
#   scripts/slurm_array.sh --tasks 3,7 exp.toml 64 4                   # rerun shards 3 and 7
#   SBATCH_EXTRA="--partition=short --account=geo" scripts/slurm_array.sh exp.toml 64
#
# Options (before the experiment):
#   --throttle M   at most M array tasks run at once (sbatch --array=...%M)
#   --tasks LIST   submit only these shards (sbatch --array syntax: 3 or 1,5-7), e.g. to
#                  rerun a cancelled or failed task; a new merge job follows them
#   --parsable     print only "ARRAY_JOB_ID MERGE_JOB_ID" on stdout
#   --help         this text
# Environment: RECONBENCH (binary; default target/release/reconbench, built if missing),
# OUT (output directory; default results/<experiment name>), SBATCH_EXTRA (more sbatch
# options for both jobs; they come last, so they override the computed --time/--mem),
# MERGE_TIME (merge job time limit in minutes, default 60).
#
# Limits: each task gets --time = ceil(cells per task / CPUS) x the file's per-cell
# `timeout` (default 600 s) + 10 % + 5 min, and, when the file sets `memory_limit_mib`,
# --mem = memory_limit_mib x CPUS + 512 MiB (the runner; the harness kills a cell over
# its limit itself). Exit codes: a task exits 1 (Slurm: FAILED) when one of its cells
# failed (run --strict), 2 on bad input, 128+signal when stopped (scancel: CANCELLED);
# the merge job runs after the array whatever its tasks' states (afterany), refuses with
# exit 3 (FAILED) while a shard is incomplete and names the tasks to rerun, and does
# nothing when an earlier merge job already merged the same shard files.
#
# Shards are deterministic (every N-th cell of the grid), and tasks run with --resume,
# so a rerun task skips the cells it already finished. Logs: <out>/slurm/. Job names:
# rb-<experiment>-shard and rb-<experiment>-merge (sacct --name=..., squeue -n ...).
set -euo pipefail

die_usage() {
    echo "slurm_array.sh: $*" >&2
    echo "usage: $0 [--throttle M] [--tasks LIST] [--parsable] EXPERIMENT.toml N_TASKS [CPUS_PER_TASK]" >&2
    exit 2
}

is_count() { [[ $1 =~ ^[1-9][0-9]*$ ]]; }

# Number of rows of a results file (0 when it does not exist): whole lines, from
# `{"key":` to the closing brace, so a line cut short by a kill is not counted (also
# not once a later append has ended it with a newline).
rows_in() {
    if [[ -f $1 ]]; then
        grep -c '^{"key":.*}$' "$1" || true
    else
        echo 0
    fi
}

# Inside Slurm: one array task, shard $SLURM_ARRAY_TASK_ID of N.
shard_job() {
    local bin="$1" exp="$2" out="$3" n="$4"
    local i="${SLURM_ARRAY_TASK_ID:?not in a Slurm array task}"
    echo "rb-shard: job ${SLURM_ARRAY_JOB_ID:-?}_$i on $(hostname) at $(date -u +%FT%TZ): shard $i/$n of $exp"
    local rc=0
    "$bin" run "$exp" --out "$out" --shard "$i/$n" --resume -j "${SLURM_CPUS_PER_TASK:-1}" --strict || rc=$?
    case $rc in
    0) echo "rb-shard: shard $i/$n done, every cell ok" ;;
    1) echo "rb-shard: shard $i/$n finished with failed cells (listed above); exit 1" ;;
    *) echo "rb-shard: shard $i/$n stopped with exit code $rc" ;;
    esac
    return "$rc"
}

# Inside Slurm: merge the N shard files into <out>/results.jsonl and write the report,
# once: only when every shard has all its cells, and only if no earlier merge job has
# already merged these shard files (the report is newer than all of them).
merge_job() {
    local bin="$1" out="$2" n="$3" cells="$4" tasks_cmd="$5" # @TASKS@: the task list
    exec 9>"$out/slurm/merge.lock"
    flock -w 600 9 || {
        echo "rb-merge: another merge job holds $out/slurm/merge.lock"
        exit 3
    }
    local i want have files=() incomplete=() newer=0
    for ((i = 0; i < n; i++)); do
        files+=("$out/results.shard-$i-of-$n.jsonl")
        want=$(((cells - i + n - 1) / n))
        have=$(rows_in "${files[i]}")
        if ((have < want)); then
            incomplete+=("$i")
            echo "rb-merge: shard $i/$n has $have of $want cells"
        fi
        [[ ${files[i]} -nt $out/report.md ]] && newer=1
    done
    if ((${#incomplete[@]})); then
        local list
        list=$(
            IFS=,
            echo "${incomplete[*]}"
        )
        echo "rb-merge: not merging, incomplete shards: $list; rerun them with:"
        echo "  ${tasks_cmd//@TASKS@/$list}"
        exit 3
    fi
    if [[ -f $out/report.md && $newer == 0 ]]; then
        echo "rb-merge: $out/report.md is newer than every shard file (an earlier merge job wrote it); nothing to do"
        exit 0
    fi
    "$bin" merge "${files[@]}" --out "$out"
    echo "rb-merge: wrote the report $out/report.md"
}

case "${1:-}" in
--shard-job)
    shift
    rc=0
    shard_job "$@" || rc=$?
    exit "$rc"
    ;;
--merge-job)
    shift
    merge_job "$@"
    exit
    ;;
esac

THROTTLE=""
TASKS=""
PARSABLE=0
while [[ ${1:-} == -* ]]; do
    case "$1" in
    --throttle)
        is_count "${2:-}" || die_usage "--throttle needs a count >= 1, got '${2:-}'"
        THROTTLE="$2"
        shift 2
        ;;
    --tasks)
        [[ ${2:-} =~ ^[0-9]+(-[0-9]+)?(,[0-9]+(-[0-9]+)?)*$ ]] ||
            die_usage "--tasks needs task ids like 3 or 1,5-7, got '${2:-}'"
        TASKS="$2"
        shift 2
        ;;
    --parsable)
        PARSABLE=1
        shift
        ;;
    -h | --help)
        # The comment block at the top of this file.
        sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
        exit 0
        ;;
    *) die_usage "unknown option $1" ;;
    esac
done
[[ $# -ge 2 && $# -le 3 ]] || die_usage "expected EXPERIMENT.toml N_TASKS [CPUS_PER_TASK]"
[[ -f $1 ]] || die_usage "no such experiment file: $1"
is_count "$2" || die_usage "N_TASKS must be a count >= 1, got '$2'"
is_count "${3:-2}" || die_usage "CPUS_PER_TASK must be a count >= 1, got '$3'"
EXP="$(realpath "$1")"
N="$2"
CPUS="${3:-2}"
MERGE_TIME="${MERGE_TIME:-60}"
is_count "$MERGE_TIME" || die_usage "MERGE_TIME must be minutes >= 1, got '$MERGE_TIME'"
command -v sbatch >/dev/null || die_usage "sbatch not found: run this on a Slurm login node"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BIN="${RECONBENCH:-$ROOT/target/release/reconbench}"
if [[ ! -x $BIN ]]; then
    (cd "$ROOT" && cargo build --release -p reconbench-cli)
fi
BIN="$(realpath "$BIN")"

# The file is checked here (exit code 2 names the problem), and the dry run's last line
# gives the experiment's name and its number of cells.
SUMMARY="$("$BIN" run "$EXP" --dry-run --shard "0/$N" | tail -n 1)"
if [[ ! $SUMMARY =~ ^(.+):\ [0-9]+\ cells\ \(of\ ([0-9]+)\)\;\ nothing\ was\ run$ ]]; then
    echo "slurm_array.sh: cannot read the dry run's summary line: '$SUMMARY'" >&2
    exit 1
fi
NAME="${BASH_REMATCH[1]}"
CELLS="${BASH_REMATCH[2]}"
((N <= CELLS)) || die_usage "N_TASKS=$N exceeds the experiment's $CELLS cells"
if [[ -n $TASKS ]]; then
    for t in ${TASKS//[,-]/ }; do
        ((t < N)) || die_usage "--tasks: task $t is not below N_TASKS=$N"
    done
fi
JOB_NAME="rb-${NAME//[^A-Za-z0-9_.-]/_}"
OUT="$(realpath -m "${OUT:-$ROOT/results/$NAME}")"
mkdir -p "$OUT/slurm"

# A top-level TOML key of the experiment (before the first [table]) as a number; empty
# when absent.
top_level_number() {
    local v
    v=$(awk -v key="$1" '
        /^[[:space:]]*\[/ { exit }
        $0 ~ "^[[:space:]]*" key "[[:space:]]*=" {
            sub(/^[^=]*=[[:space:]]*/, ""); sub(/[[:space:]]*(#.*)?$/, ""); print; exit
        }' "$EXP")
    if [[ -n $v && ! $v =~ ^[0-9]+(\.[0-9]+)?$ ]]; then
        echo "slurm_array.sh: $1 = $v in $EXP is not a plain number; give the limit with SBATCH_EXTRA" >&2
        exit 2
    fi
    echo "$v"
}
TIMEOUT_S="$(top_level_number timeout)"
MEM_MIB="$(top_level_number memory_limit_mib)"
PER_TASK=$(((CELLS + N - 1) / N))
ROUNDS=$(((PER_TASK + CPUS - 1) / CPUS))
TIME_S=$(awk -v r="$ROUNDS" -v t="${TIMEOUT_S:-600}" 'BEGIN { s = r * t * 1.1 + 300; print int(s) + (s > int(s)) }')
LIMITS=(--time="$(((TIME_S + 59) / 60))")
if [[ -n $MEM_MIB ]]; then
    LIMITS+=(--mem="$((MEM_MIB * CPUS + 512))M")
fi
ARRAY="${TASKS:-0-$((N - 1))}${THROTTLE:+%$THROTTLE}"
# shellcheck disable=SC2206 # SBATCH_EXTRA is a list of options, split on spaces.
EXTRA=(${SBATCH_EXTRA:-})
SELF="$ROOT/scripts/slurm_array.sh"
RERUN="OUT=$OUT $SELF --tasks @TASKS@ ${THROTTLE:+--throttle $THROTTLE }$EXP $N $CPUS"

# sbatch --parsable ARGS...; prints the job id, or fails naming what happened.
submit() {
    local id
    id=$(sbatch --parsable "$@") || {
        echo "slurm_array.sh: sbatch failed (see its message above)" >&2
        exit 1
    }
    id="${id%%;*}"
    [[ $id =~ ^[0-9]+$ ]] || {
        echo "slurm_array.sh: sbatch gave no job id: '$id'" >&2
        exit 1
    }
    echo "$id"
}
ARRAY_JOB=$(submit \
    --job-name="$JOB_NAME-shard" \
    --array="$ARRAY" \
    --ntasks=1 --cpus-per-task="$CPUS" \
    "${LIMITS[@]}" \
    --output="$OUT/slurm/shard-%a-of-$N.%A.out" \
    "${EXTRA[@]}" \
    "$SELF" --shard-job "$BIN" "$EXP" "$OUT" "$N")
MERGE_JOB=$(submit \
    --job-name="$JOB_NAME-merge" \
    --dependency="afterany:$ARRAY_JOB" \
    --ntasks=1 --cpus-per-task=1 \
    --time="$MERGE_TIME" \
    --output="$OUT/slurm/merge.%j.out" \
    "${EXTRA[@]}" \
    "$SELF" --merge-job "$BIN" "$OUT" "$N" "$CELLS" "$RERUN") || {
    echo "slurm_array.sh: array job $ARRAY_JOB was submitted, its merge job was not" >&2
    exit 1
}

if ((PARSABLE)); then
    echo "$ARRAY_JOB $MERGE_JOB"
else
    echo "submitted array job $ARRAY_JOB (tasks $ARRAY of $N, $CELLS cells, ${LIMITS[*]} each) and merge job $MERGE_JOB"
    echo "logs: $OUT/slurm/; report: $OUT/report.md once the merge job has run"
fi

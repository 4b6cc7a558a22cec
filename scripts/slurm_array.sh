#!/usr/bin/env bash
# Run a reconbench experiment as a Slurm job array: task i runs shard i/N of the grid,
# writing results/<name>/results.shard-i-of-N.jsonl; a dependent job merges the shards
# and writes the report.
#
#   scripts/slurm_array.sh experiments/quickstart.toml 16            # submit 16 tasks
#   SBATCH_EXTRA="--partition=short --time=01:00:00" scripts/slurm_array.sh exp.toml 64
#
# Shards are deterministic (every N-th cell of the grid), so a failed task can be rerun
# alone (sbatch --array=<i> ...), with --resume it skips the cells it already finished.
# Keep N <= MaxArraySize of your cluster (often 1001). Each task runs its cells with
# `-j $SLURM_CPUS_PER_TASK` worker processes.
set -euo pipefail

if [[ $# -lt 2 ]]; then
    echo "usage: $0 EXPERIMENT.toml N_TASKS [CPUS_PER_TASK]" >&2
    exit 2
fi
EXP="$1"
N="$2"
CPUS="${3:-2}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BIN="${RECONBENCH:-$ROOT/target/release/reconbench}"
NAME="$(basename "$EXP" .toml)"
OUT="${OUT:-$ROOT/results/$NAME}"

if [[ ! -x "$BIN" ]]; then
    (cd "$ROOT" && cargo build --release -p reconbench-cli)
fi
# Fail early on a bad experiment file (exit code 2 names the problem).
"$BIN" run "$EXP" --dry-run --shard "0/$N"
mkdir -p "$OUT/slurm"

ARRAY_JOB=$(sbatch --parsable ${SBATCH_EXTRA:-} \
    --job-name="rb-$NAME" \
    --array="0-$((N - 1))" \
    --cpus-per-task="$CPUS" \
    --output="$OUT/slurm/%A_%a.out" \
    --wrap="cd '$ROOT' && '$BIN' run '$EXP' --out '$OUT' --shard \${SLURM_ARRAY_TASK_ID}/$N --resume -j \${SLURM_CPUS_PER_TASK:-1}")

MERGE_JOB=$(sbatch --parsable ${SBATCH_EXTRA:-} \
    --job-name="rb-$NAME-merge" \
    --dependency="afterany:$ARRAY_JOB" \
    --cpus-per-task=1 \
    --output="$OUT/slurm/merge_%j.out" \
    --wrap="cd '$ROOT' && '$BIN' merge '$OUT' --out '$OUT'")

echo "submitted array job $ARRAY_JOB ($N tasks) and merge job $MERGE_JOB"
echo "results: $OUT/report.md once the merge job has run"

#!/usr/bin/env bash
# Render a reference across a cluster as a Slurm job array, then merge it.
#
#   sbatch --array=0-15 scripts/reference-slurm.sh cornell 65536
#   # when all tasks are done (or: sbatch --dependency=afterok:<jobid> --wrap ...):
#   cargo run --release -- merge cornell --out results
#
# The output root is results/ (relative to the submit directory) unless DIBENCH_OUT names
# another: sbatch --export=ALL,DIBENCH_OUT=/shared/refs --array=0-15 scripts/reference-slurm.sh …
# then merge with --out /shared/refs. The shard count is the array's size unless DIBENCH_SHARDS
# gives it: to redo task 2 of a 16-task array alone,
#   sbatch --export=ALL,DIBENCH_SHARDS=16 --array=2 scripts/reference-slurm.sh cornell 65536
# scripts/test-slurm.sh runs all this on a one-node cluster.
#
# Each task renders shard i = $SLURM_ARRAY_TASK_ID of the n shards (passes i, i+n, …
# of SPP) with the same random streams a single process would use, into
# <out>/<scene>/reference/shards/; `dibench merge` combines them losslessly. The output
# root must be on a filesystem every node sees.
#SBATCH --job-name=dibench-reference
#SBATCH --cpus-per-task=16
#SBATCH --time=02:00:00
#SBATCH --output=dibench-reference-%A_%a.log
set -euo pipefail
scene=${1:?usage: sbatch --array=0-N scripts/reference-slurm.sh SCENE SPP [SEED]}
spp=${2:?total samples per pixel}
seed=${3:-1}
: "${SLURM_ARRAY_TASK_ID:?run as a job array (sbatch --array=...)}"
: "${SLURM_ARRAY_TASK_COUNT:?run as a job array (sbatch --array=...)}"
shards=${DIBENCH_SHARDS:-$SLURM_ARRAY_TASK_COUNT}
cd "${SLURM_SUBMIT_DIR:-$(dirname "$0")/..}"
# Build once beforehand (cargo build --release) so tasks do not race on target/; DIBENCH_BIN
# names another binary (with --export=ALL,DIBENCH_BIN=...).
exec "${DIBENCH_BIN:-./target/release/dibench}" reference "$scene" --spp "$spp" --seed "$seed" \
  --shard "${SLURM_ARRAY_TASK_ID}/${shards}" \
  ${SLURM_CPUS_PER_TASK:+--threads "$SLURM_CPUS_PER_TASK"} --out "${DIBENCH_OUT:-results}"

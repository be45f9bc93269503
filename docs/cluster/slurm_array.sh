#!/usr/bin/env bash
# A Slurm job array over the points of an experiment (or the frames of `parallax upsample`):
# each array task runs one shard; Slurm sets SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT,
# which `parallax run` and `parallax upsample` read when --shard is absent. A last job,
# started after the array, merges the shards into the output of one unsharded run.
#
#   sbatch docs/cluster/slurm_array.sh experiments/widmer_table2_warp.toml
#   # when the array is done (or chain it: sbatch --dependency=afterok:<jobid> ...):
#   parallax merge out/shards/widmer_table2_warp/shard-* --out out/experiments/widmer_table2_warp
#
#SBATCH --job-name=parallax-run
#SBATCH --array=0-3
#SBATCH --cpus-per-task=8
#SBATCH --mem=8G
#SBATCH --time=02:00:00
#SBATCH --output=out/shards/slurm-%A_%a.log
set -euo pipefail
EXPERIMENT=${1:?usage: sbatch slurm_array.sh EXPERIMENT.toml}
NAME=$(basename "$EXPERIMENT" .toml)
PARALLAX=${PARALLAX:-target/release/parallax}
# Each task writes its own folder: shard.json + its points' images.
"$PARALLAX" --threads "${SLURM_CPUS_PER_TASK:-1}" run "$EXPERIMENT" \
  --out "out/shards/$NAME/shard-$SLURM_ARRAY_TASK_ID"

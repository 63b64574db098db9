#!/usr/bin/env bash
# hairfit batch as a Slurm job array: one array task per shard, then one merge job.
#
#   sbatch --array=0-7 scripts/slurm-array.sh fits.csv fits/batch     # 8 shards
#   sbatch --dependency=afterok:JOBID --wrap "hairfit batch fits.csv --out fits/batch --merge"
#
# Each task runs `hairfit batch --shard auto`, which reads SLURM_ARRAY_TASK_ID, _MIN and _COUNT:
# task k fits manifest items k, k+8, k+16, … into fits/batch/NAME/. A pre-empted or failed task
# can simply be resubmitted: finished items are skipped. Edit the resources to your cluster.
#SBATCH --job-name=hairfit
#SBATCH --cpus-per-task=4
#SBATCH --mem=4G
#SBATCH --time=02:00:00
#SBATCH --output=hairfit-%A_%a.log
set -euo pipefail
manifest=${1:?usage: sbatch --array=0-N scripts/slurm-array.sh MANIFEST OUTDIR}
out=${2:?usage: sbatch --array=0-N scripts/slurm-array.sh MANIFEST OUTDIR}
# Each fit uses every core Slurm gave the task.
export RAYON_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}
exec hairfit batch "$manifest" --out "$out" --shard auto

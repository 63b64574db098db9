#!/usr/bin/env bash
# hairfit batch as a Slurm job array: one array task per shard, then one merge job.
#
#   jobid=$(sbatch --parsable --array=0-7 scripts/slurm-array.sh fits.csv fits/batch)   # 8 shards
#   sbatch --dependency=afterany:$jobid --wrap "hairfit batch fits.csv --out fits/batch --merge"
#
# The merge waits for every task however it ended (afterany: with afterok one failed item
# would keep it pending forever); it writes summary.csv and index.html, then exits 1 naming the
# items that failed, were interrupted or are missing.
#
# Each task runs `hairfit batch --shard auto`, which reads SLURM_ARRAY_TASK_ID, _MIN, _STEP and
# _COUNT (shard K = (ID - MIN) / STEP, so stepped arrays like --array=0-28:4 work): task k fits
# manifest items k, k+8, k+16, … into fits/batch/NAME/.
#
# Re-running: finished items are always skipped, so after a pre-emption or a failure resubmit
# the WHOLE array (same --array range). Do not resubmit a single task as `sbatch --array=3`:
# that array has one task (COUNT=1), so `--shard auto` would run the whole manifest in it. To
# re-run one shard alone, name it: `sbatch --wrap "hairfit batch fits.csv --out fits/batch --shard 3/8"`.
# Edit the resources to your cluster.
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

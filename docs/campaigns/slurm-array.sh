#!/usr/bin/env bash
# One job of independent frames (track = false in job.toml) measured by a
# Slurm job array: task K of N measures part K of the frames, writing the
# frames' files to the job's out_dir and its rows to
# summary.shard-K-of-N.csv; the last step joins the parts into summary.csv,
# the single run's byte for byte.
#
#   sbatch --array=1-16 docs/campaigns/slurm-array.sh campaign/job.toml
#   # when every task has ended:
#   vicurve merge campaign/results
#
# A tracked sequence is not split (each frame starts from the one before):
# give each sequence its own job file and let task K run job file K, e.g.
#   JOB=$(sed -n "${SLURM_ARRAY_TASK_ID}p" jobs.txt); vicurve run "$JOB"
#
#SBATCH --job-name=vicurve
#SBATCH --cpus-per-task=2
#SBATCH --time=01:00:00
#SBATCH --output=vicurve-%A_%a.log
set -euo pipefail
JOB="${1:?usage: sbatch --array=1-N slurm-array.sh JOB.toml}"
# Re-running a task skips the frames it already measured (resume).
exec vicurve run "$JOB" --shard "${SLURM_ARRAY_TASK_ID}/${SLURM_ARRAY_TASK_COUNT}"

#!/usr/bin/env bash
# Batch precompute as a Slurm job array: array task i builds data row i of the
# shapes CSV (`sflsh precompute --task-index $SLURM_ARRAY_TASK_ID`).
#
# Every node must see the same paths (a shared file system): the sflsh
# executable, the shapes CSV, the body model file, OUT_DIR and CACHE_DIR (the
# template-stage cache). Build the template stage once before the array, so the
# tasks load it instead of each building it:
#
#   N=$(build/sflsh -q precompute --batch shapes.csv --out-dir avatars --dry-run | sed -n 's/^batch summary: \([0-9]*\) rows.*/\1/p')
#   build/sflsh precompute --template-only --cache-dir /shared/sflsh-cache [options]
#   SHAPES=shapes.csv OUT_DIR=avatars CACHE_DIR=/shared/sflsh-cache SFLSH_OPTIONS="--handles 64" \
#     sbatch --array=0-$((N - 1)) scripts/precompute_slurm.sh
#
# (or chain them: `jid=$(sbatch --parsable --wrap "build/sflsh precompute --template-only ...")`,
# then `sbatch --dependency=afterok:$jid --array=... scripts/precompute_slurm.sh`).
# `--array=0-999%50` caps the tasks running at once. A task whose output already
# exists returns at once, so resubmitting the whole array after a failure
# rebuilds only what is missing. Each task writes OUT_DIR/manifest-task-<i>.csv;
# afterwards one local run with every row done (it builds nothing) collects them:
#   build/sflsh precompute --batch shapes.csv --out-dir avatars --cache-dir /shared/sflsh-cache [options] --jobs 1
# writes avatars/manifest.csv (row, name, key, file, status) for the whole file.
#
# Environment: SHAPES, OUT_DIR (required), SFLSH (default build/sflsh next to
# this script), CACHE_DIR (default $SFLSH_CACHE_DIR or ~/.cache/sflsh),
# SFLSH_OPTIONS (extra precompute options, the same for the template step).
#SBATCH --job-name=sflsh-precompute
#SBATCH --array=0-15
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=2
#SBATCH --mem=4G
#SBATCH --time=01:00:00
#SBATCH --output=sflsh-precompute-%A_%a.log
set -euo pipefail

: "${SHAPES:?set SHAPES to the shapes CSV}"
: "${OUT_DIR:?set OUT_DIR to the output folder}"
: "${SLURM_ARRAY_TASK_ID:?run this with sbatch --array=0-(rows-1)}"
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# sbatch copies the script to a spool folder: prefer SLURM_SUBMIT_DIR for relative defaults.
SFLSH=${SFLSH:-${SLURM_SUBMIT_DIR:-$here}/build/sflsh}
CACHE_DIR=${CACHE_DIR:-${SFLSH_CACHE_DIR:-$HOME/.cache/sflsh}}

# shellcheck disable=SC2086  # SFLSH_OPTIONS is a list of words
exec "$SFLSH" -q precompute ${SFLSH_OPTIONS:-} --cache-dir "$CACHE_DIR" \
  --batch "$SHAPES" --out-dir "$OUT_DIR" --task-index "$SLURM_ARRAY_TASK_ID"

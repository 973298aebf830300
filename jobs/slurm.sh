#!/usr/bin/env bash
# psph on SLURM. Runs SCENE on the job's tasks with srun; 120 s before the wall-time
# limit SLURM sends SIGTERM to every rank, psph writes OUT/checkpoint.h5 and exits 75,
# and this script submits itself again to continue from the checkpoint.
#
#   sbatch --export=ALL,SCENE=retrogressive_k0_0.5,OUT=runs/retro jobs/slurm.sh
#
# Environment: SCENE (required), OUT (runs/<scene>), PSPH_DIR (checkout with .venv,
# default: the submit directory), MODULES (modules to load, e.g. "openmpi hdf5-mpi"),
# MAX_RESUBMITS (20), EXTRA (more `psph run` arguments).
#SBATCH --job-name=psph
#SBATCH --nodes=1
#SBATCH --ntasks=2
#SBATCH --cpus-per-task=1
#SBATCH --time=01:00:00
#SBATCH --signal=TERM@120
#SBATCH --output=psph-%j.log
set -uo pipefail
SCENE=${SCENE:?set SCENE: sbatch --export=ALL,SCENE=name jobs/slurm.sh}
OUT=${OUT:-runs/$(basename "$SCENE" .toml)}
PSPH_DIR=${PSPH_DIR:-${SLURM_SUBMIT_DIR:-$PWD}}
MAX_RESUBMITS=${MAX_RESUBMITS:-20}
RESUBMIT=${RESUBMIT:-0}
EXTRA=${EXTRA:-}
JOB_SCRIPT=${JOB_SCRIPT:-$PSPH_DIR/jobs/slurm.sh}

cd "$PSPH_DIR"
if [ -n "${MODULES:-}" ]; then module load $MODULES; fi
source .venv/bin/activate
export NUMBA_NUM_THREADS=1 OMP_NUM_THREADS=1

restart=()
if [ -f "$OUT/checkpoint.h5" ] && ! grep -qs '"status": "finished"' "$OUT/summary.json"; then
  restart=(--restart "$OUT/checkpoint.h5")
fi
srun python -m psph run "$SCENE" --out "$OUT" --quiet "${restart[@]}" $EXTRA
rc=$?
if [ $rc -eq 75 ] && [ "$RESUBMIT" -lt "$MAX_RESUBMITS" ]; then
  sbatch --export=ALL,RESUBMIT=$((RESUBMIT + 1)),SCENE="$SCENE",OUT="$OUT" "$JOB_SCRIPT"
fi
exit $rc

#!/usr/bin/env bash
# psph on PBS Pro / Torque. PBS gives no warning before the wall-time limit, so the run
# is stopped WALL_MARGIN seconds early: `timeout` sends SIGUSR1 to mpirun, which forwards
# it to every rank; psph writes OUT/checkpoint.h5 and exits 75, and this script submits
# itself again to continue from the checkpoint.
#
#   qsub -v SCENE=retrogressive_k0_0.5,OUT=runs/retro jobs/pbs.sh
#
# Environment: SCENE (required), OUT (runs/<scene>), NP (ranks, 2), WALL_SECONDS (must
# match the walltime below, 3600), WALL_MARGIN (180), PSPH_DIR (checkout with .venv,
# default: the submit directory), MODULES, MAX_RESUBMITS (20), EXTRA.
#PBS -N psph
#PBS -l select=1:ncpus=2:mpiprocs=2
#PBS -l walltime=01:00:00
#PBS -j oe
set -uo pipefail
SCENE=${SCENE:?set SCENE: qsub -v SCENE=name jobs/pbs.sh}
OUT=${OUT:-runs/$(basename "$SCENE" .toml)}
PSPH_DIR=${PSPH_DIR:-${PBS_O_WORKDIR:-$PWD}}
NP=${NP:-2}
WALL_SECONDS=${WALL_SECONDS:-3600}
WALL_MARGIN=${WALL_MARGIN:-180}
MAX_RESUBMITS=${MAX_RESUBMITS:-20}
RESUBMIT=${RESUBMIT:-0}
EXTRA=${EXTRA:-}

cd "$PSPH_DIR"
if [ -n "${MODULES:-}" ]; then module load $MODULES; fi
source .venv/bin/activate
export NUMBA_NUM_THREADS=1 OMP_NUM_THREADS=1

restart=()
if [ -f "$OUT/checkpoint.h5" ] && ! grep -qs '"status": "finished"' "$OUT/summary.json"; then
  restart=(--restart "$OUT/checkpoint.h5")
fi
timeout --preserve-status --signal=USR1 --kill-after=120 $((WALL_SECONDS - WALL_MARGIN)) \
  mpirun -n "$NP" python -m psph run "$SCENE" --out "$OUT" --quiet "${restart[@]}" $EXTRA
rc=$?
if [ $rc -eq 75 ] && [ "$RESUBMIT" -lt "$MAX_RESUBMITS" ]; then
  qsub -v "SCENE=$SCENE,OUT=$OUT,NP=$NP,RESUBMIT=$((RESUBMIT + 1)),PSPH_DIR=$PSPH_DIR" \
    "$PSPH_DIR/jobs/pbs.sh"
fi
exit $rc

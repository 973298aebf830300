#!/usr/bin/env bash
# psph local launcher: runs SCENE on NP ranks with mpirun; with WALL set, each segment
# stops after WALL seconds (SIGUSR1, which mpirun forwards to every rank), writes
# OUT/checkpoint.h5 and is restarted from it, until the run finishes.
#
#   jobs/local.sh SCENE [OUT]
#   NP=2 WALL=600 jobs/local.sh retrogressive_k0_0.5 runs/retro
#
# Environment: NP (ranks, 2), WALL (seconds per segment; empty: one segment),
# MAX_SEGMENTS (50), PSPH_DIR (the psph checkout, default: this script's parent),
# EXTRA (more arguments for `psph run`, e.g. "--set time.end=40").
# Exit status: that of the last segment (0 done, 2 bad input, 3 numerical failure).
set -uo pipefail
SCENE=${1:?usage: jobs/local.sh SCENE [OUT]}
PSPH_DIR=${PSPH_DIR:-$(cd "$(dirname "$0")/.." && pwd)}
OUT=${2:-runs/$(basename "$SCENE" .toml)}
NP=${NP:-2}
WALL=${WALL:-}
MAX_SEGMENTS=${MAX_SEGMENTS:-50}
EXTRA=${EXTRA:-}
PY="$PSPH_DIR/.venv/bin/python"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl=self,vader,tcp
export OMPI_MCA_btl_vader_single_copy_mechanism=none
export NUMBA_NUM_THREADS=1 OMP_NUM_THREADS=1

rc=75
for ((segment = 1; segment <= MAX_SEGMENTS && rc == 75; segment++)); do
  restart=()
  # continue an unfinished run (interrupted, or stopped by a failure) from its checkpoint
  if [ -f "$OUT/checkpoint.h5" ] && ! grep -qs '"status": "finished"' "$OUT/summary.json"
  then
    restart=(--restart "$OUT/checkpoint.h5")
  fi
  echo "jobs/local.sh: segment $segment: $SCENE -> $OUT ${restart[*]}" >&2
  if [ -n "$WALL" ]; then
    timeout --preserve-status --signal=USR1 --kill-after=300 "$WALL" \
      mpirun -n "$NP" "$PY" -m psph run "$SCENE" --out "$OUT" --quiet "${restart[@]}" $EXTRA
  else
    mpirun -n "$NP" "$PY" -m psph run "$SCENE" --out "$OUT" "${restart[@]}" $EXTRA
  fi
  rc=$?
  # the wall-time SIGUSR1 can reach a rank outside its recording handler: before Python
  # runs psph's first line, or after the interpreter restored the default handlers on its
  # way out (exit 128 + 10, seen in CI on a loaded machine). A finished run is finished;
  # otherwise continue from the checkpoint as after any stop.
  if [ "$rc" -eq 138 ]; then
    if grep -qs '"status": "finished"' "$OUT/summary.json"; then rc=0; else rc=75; fi
  fi
done
exit $rc

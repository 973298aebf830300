"""A bench's runs of psph scenes: `mpirun -n NP python -m psph run SCENE --out OUT --set ...`
as a user starts them, a finished one kept with `reuse`, its summary.json returned.
Imported by the verification benches (`collapse_saturated_3d.py`, `slope_3d.py`)."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none", "NUMBA_NUM_THREADS": "1"}


def run_scene(out: Path, scene: str, ranks: int, settings: list[str], reuse: bool) -> dict:
    """Run `scene` into `out` on `ranks` ranks (1: no mpirun) with `--set` `settings`;
    with `reuse` a finished run in `out` is kept. SystemExit with the stderr's tail if
    the run fails."""
    summary = out / "summary.json"
    if reuse and summary.is_file() and json.loads(summary.read_text())["status"] == "finished":
        return json.loads(summary.read_text())
    cmd = [sys.executable, "-m", "psph", "run", scene, "--out", str(out), "--quiet"]
    for s in settings:
        cmd += ["--set", s]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks)] + cmd
    print("  " + " ".join(cmd), flush=True)
    r = subprocess.run(cmd, cwd=ROOT, env={**os.environ, **MPI_ENV}, capture_output=True,
                       text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr[-2000:]}")
    return json.loads(summary.read_text())

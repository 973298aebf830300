"""Every bench script runs against the code as it is.

Each script under bench/ (found by glob: a new one is covered without being listed) runs its
smallest case, `--quick` (or the case named in `ARGS`), with `--out` a scratch directory,
and must exit 0; those whose smallest case is still longer than this suite's budget (about 4
minutes on 2 cores, one worker; 2 min 15 s measured near idle) run `--help` only
(`HELP_ONLY`, each with its smallest case's time). The modules in `LIBRARIES` are imported
by scripts, not run. `MPIRUN`: the scripts measured on the ranks they are started on,
launched under `mpirun -n 2`.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "bench"
LIBRARIES = {"verification/scene_runs.py"}
# the smallest case is over this suite's budget: its wall time, measured on the 2-core
# machine near idle (every one of them exits 0 there)
HELP_ONLY = {
    "performance/compare_revisions.py": "two git worktrees, each compiling its kernels",
    "performance/field.py": "25 s on 2 ranks",
    "performance/halo_layouts.py": "17 s on 4 ranks",
    "performance/large_run.py": "30 s on 1, 2 and 4 ranks",
    "performance/memory.py": "22 s on 1 and 2 ranks",
    "performance/scaling_model.py": "38 s on 1, 2 and 4 ranks",
    "performance/scaling_model_3d.py": "37 s on 1, 2 and 4 ranks, 3D",
    "verification/collapse_saturated_3d.py": "26 s, a 3D slab on 2 ranks",
    "verification/slope_3d.py": "149 s, a 3D slab on 2 ranks",
}
ARGS = {
    "verification/convergence.py": ["--smoke"],
    "verification/time_vs_error.py": ["--smoke"],
    "tools/slope_3d_grids.py": [],  # seconds as it is
    "tools/docs_figure.py": None,  # SRC DST: a picture made here
}
MPIRUN = {"performance/throughput.py", "verification/default_run.py"}
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none", "NUMBA_NUM_THREADS": "1",
           "OMP_NUM_THREADS": "1"}
SCRIPTS = sorted(p.relative_to(BENCH).as_posix() for p in BENCH.rglob("*.py")
                 if p.relative_to(BENCH).as_posix() not in LIBRARIES)


def _command(script: str, out: Path) -> list[str]:
    """The script's smallest case (or --help) with its output under `out`."""
    cmd = [sys.executable, str(BENCH / script)]
    if script in HELP_ONLY:
        return cmd + ["--help"]
    if script == "tools/docs_figure.py":
        from PIL import Image

        src = out / "wide.png"
        Image.fromarray(np.zeros((20, 40, 3), np.uint8)).save(src)
        return cmd + [str(src), str(out / "narrow.png"), "--width", "10"]
    args = ARGS.get(script, ["--quick"])
    cmd += args + ["--out", str(out)]
    if script in MPIRUN:
        cmd = ["mpirun", "-n", "2"] + cmd
    return cmd


def test_every_script_is_known_or_runs_its_quick_case():
    """The lists name scripts that exist (a moved or removed one is taken off them)."""
    listed = set(HELP_ONLY) | set(ARGS) | MPIRUN | LIBRARIES
    assert listed <= set(SCRIPTS) | LIBRARIES, listed - set(SCRIPTS)
    assert all((BENCH / lib).is_file() for lib in LIBRARIES)


@pytest.mark.parametrize("script", SCRIPTS)
def test_bench_script_runs(script, tmp_path):
    if script in MPIRUN and shutil.which("mpirun") is None:
        pytest.skip("needs mpirun")
    cmd = _command(script, tmp_path)
    res = subprocess.run(cmd, cwd=tmp_path, env={**os.environ, **MPI_ENV},
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, f"{' '.join(cmd)}\n{res.stdout[-1500:]}\n{res.stderr[-3000:]}"
    if script in HELP_ONLY:
        assert "--quick" in res.stdout or "--smoke" in res.stdout, res.stdout
    elif script != "tools/docs_figure.py":
        assert any(tmp_path.iterdir()), f"{script} wrote nothing into --out"

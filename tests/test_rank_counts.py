"""The same run on 1 and 2 ranks gives the same particles, bit for bit, through migration
and two removals, and so does its 2-rank checkpoint restarted on 4 ranks (issue 15;
`make bench-ranks` compares whole runs on 1 to 4 ranks).

The 2- and 4-rank runs are `mpirun` subprocesses of the command line, as a user starts
them (4 ranks share this machine's 2 cores: slower, not different)."""

import os
import shutil
import subprocess
import sys

from psph.app.run import run
from psph.config.load import load_scene
from tests.helpers import compare_runs, falling_far
from tests.test_removal import REMOVE

SETTINGS = REMOVE + ["time.end=0.15"]
CHECKPOINT = ["checkpoint.every=3500", "checkpoint.at_end=false"]  # between the removals


def _mpirun(ranks: int, scene, out, *extra: str, restart=None) -> None:
    _mpirun_scene(ranks, scene, out, SETTINGS + list(extra), restart=restart)


def _mpirun_scene(ranks: int, scene, out, settings: list[str], restart=None) -> None:
    """`mpirun -n ranks psph run scene --set ...` as a user starts it; asserts exit 0."""
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")
    cmd = ["mpirun", "-n", str(ranks), sys.executable, "-m", "psph", "run", str(scene),
           "--out", str(out), "--quiet"]
    for assignment in settings:
        cmd += ["--set", assignment]
    if restart is not None:
        cmd += ["--restart", str(restart)]
    res = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]


def test_one_and_two_ranks_and_a_restart_on_four_agree(tmp_path):
    from mpi4py import MPI

    scene = falling_far(tmp_path)
    run(load_scene(str(scene), SETTINGS), tmp_path / "one", comm=MPI.COMM_SELF, quiet=True)
    _mpirun(2, scene, tmp_path / "two", *CHECKPOINT)
    shutil.copytree(tmp_path / "two", tmp_path / "two_then_four")
    _mpirun(4, scene, tmp_path / "two_then_four", *CHECKPOINT,
            restart=tmp_path / "two_then_four" / "checkpoint.h5")
    one = tmp_path / "one" / "particles.h5"
    for other in ("two", "two_then_four"):
        assert compare_runs(one, tmp_path / other / "particles.h5") is None, other

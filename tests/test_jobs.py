"""The job scripts: shell syntax, and the local launcher carrying a run through several
wall-time segments (SIGUSR1 through mpirun -> checkpoint -> exit 75 -> restart)."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from psph.io.snapshots import read_snapshots

JOBS = Path(__file__).parent.parent / "jobs"


@pytest.mark.parametrize("script", ["local.sh", "slurm.sh", "pbs.sh"])
def test_job_script_syntax(script):
    r = subprocess.run(["bash", "-n", str(JOBS / script)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


@pytest.mark.skipif(shutil.which("mpirun") is None, reason="needs mpirun")
def test_local_launcher_finishes_a_run_over_several_segments(tmp_path):
    out = tmp_path / "run"
    # 0.1 s (20,000 TPI steps) is two or more 7 s segments on an idle machine; the segment
    # budget leaves room for a loaded one (the test is about continuity across segments,
    # not speed)
    env = dict(os.environ, NP="2", WALL="7", MAX_SEGMENTS="40",
               EXTRA="--set particles.dx=0.02 --set material.k=8e-4 --set time.end=0.1 "
                     "--set verification.tv=[] --set output.interval=0.025")
    r = subprocess.run([str(JOBS / "local.sh"), "terzaghi_tpi", str(out)], env=env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "segment 2:" in r.stderr, r.stderr[-3000:]  # at least one wall-time stop
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "finished" and summary["restarted_from"]
    steps = [s["step"] for s in read_snapshots(out / "particles.h5")]
    times = [s["time"] for s in read_snapshots(out / "particles.h5")]
    assert steps == sorted(set(steps)) and abs(times[-1] - 0.1) < 5e-6  # within one step
    assert len(steps) == 5  # t = 0, 0.025, ..., 0.1: none lost or doubled across segments

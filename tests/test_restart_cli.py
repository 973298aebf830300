"""Checkpoint/restart, stop signals, export and unreadable files through the command line
(one rank, subprocesses)."""

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from psph.io.checkpoint import read_checkpoint
from psph.io.snapshots import read_snapshots

SMALL = ["--set", "particles.dx=0.02", "--set", "material.k=8e-4", "--set",
         "verification.tv=[]", "--set", "output.times=[0.005]"]


def cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "psph", *args], capture_output=True,
                          text=True, timeout=300, **kw)


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("cli") / "run"
    r = cli("run", "terzaghi_tpi", "--out", str(out), "--quiet", *SMALL, "--set", "time.end=0.006")
    assert r.returncode == 0, r.stderr
    return out


def test_sigterm_checkpoints_and_exits_75_then_restart_finishes(tmp_path):
    out = tmp_path / "run"
    args = ["run", "terzaghi_tpi", "--out", str(out), "--quiet", *SMALL]
    proc = subprocess.Popen([sys.executable, "-m", "psph", *args, "--set", "time.end=1.0"],
                            stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    while not (out / "particles.xdmf").exists():  # the loop is running
        assert proc.poll() is None and time.time() - t0 < 120, proc.stderr.read()
        time.sleep(0.05)
    time.sleep(0.3)
    proc.send_signal(signal.SIGTERM)
    err = proc.communicate(timeout=120)[1]
    assert proc.returncode == 75, err
    assert "stopped by SIGTERM" in err and "--restart" in err and "Traceback" not in err
    meta, arrays = read_checkpoint(out / "checkpoint.h5")
    assert 0 < meta["t"] < 1.0 and np.all(np.isfinite(arrays["x"]))
    assert not (out / "checkpoint.h5.tmp").exists()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    # continue to a little later than the checkpoint; --out defaults to its directory
    r = cli("run", "terzaghi_tpi", "--quiet", *SMALL, "--set", f"time.end={meta['t'] + 1e-3!r}",
            "--restart", str(out / "checkpoint.h5"))
    assert r.returncode == 0, r.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "finished" and summary["restarted_from"]
    assert summary["steps"] > meta["step"]
    steps = [s["step"] for s in read_snapshots(out / "particles.h5")]
    assert steps == sorted(set(steps)) and steps[-1] == summary["steps"]


def test_a_stop_signal_during_start_up_is_honoured_not_fatal(tmp_path):
    """SIGUSR1 while Python still imports (numba, mpi4py, h5py take about a second): the
    process used to die of the signal's default action (exit -10), which a scheduler's
    fixed wall-time signal hit in jobs/local.sh when a segment started or finished near
    it. Now it is recorded and the run stops at once with its checkpoint (exit 75)."""
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "psph", "run", "terzaghi_tpi", "--out",
                             str(out), "--quiet", *SMALL, "--set", "time.end=1.0"],
                            stderr=subprocess.PIPE, text=True)
    time.sleep(0.3)
    assert proc.poll() is None
    proc.send_signal(signal.SIGUSR1)
    err = proc.communicate(timeout=120)[1]
    assert proc.returncode == 75, err
    assert "stopped by SIGUSR1" in err and "Traceback" not in err
    assert read_checkpoint(out / "checkpoint.h5")[0]["t"] < 1.0


def test_restart_refuses_changed_physics(finished):
    r = cli("run", "terzaghi_tpi", "--quiet", *SMALL, "--set", "time.end=0.006",
            "--set", "material.E=3e7", "--restart", str(finished / "checkpoint.h5"))
    assert r.returncode == 2
    line = r.stderr.strip()
    assert len(line.splitlines()) == 1
    assert "material.E" in line and "differs from the checkpoint" in line


@pytest.mark.parametrize("damage", ["truncate", "garbage", "incomplete", "missing"])
def test_unreadable_checkpoint_is_one_line_exit_2(finished, tmp_path, damage):
    bad = tmp_path / "checkpoint.h5"
    src = (finished / "checkpoint.h5").read_bytes()
    if damage == "truncate":
        bad.write_bytes(src[: len(src) // 2])
    elif damage == "garbage":
        bad.write_bytes(b"not hdf5 at all" * 100)
    elif damage == "incomplete":
        bad.write_bytes(src)
        with h5py.File(bad, "a") as f:
            del f.attrs["complete"]
    r = cli("run", "terzaghi_tpi", "--out", str(tmp_path / "o"), *SMALL, "--set", "time.end=0.006",
            "--restart", str(bad))
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert str(bad) in r.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("command", ["plot", "export"])
def test_truncated_particles_h5_is_one_line_exit_2(finished, tmp_path, command):
    out = tmp_path / "copy"
    out.mkdir()
    for f in ("scene.toml", "history.csv", "summary.json"):
        (out / f).write_bytes((finished / f).read_bytes())
    src = (finished / "particles.h5").read_bytes()
    (out / "particles.h5").write_bytes(src[: len(src) // 3])
    r = cli(command, str(out))
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert "particles.h5" in r.stderr


def test_export_vtu_round_trips_through_meshio(finished):
    import meshio

    r = cli("export", str(finished), "--format", "vtu")
    assert r.returncode == 0, r.stderr
    snaps = read_snapshots(finished / "particles.h5")
    pvd = (finished / "particles.pvd").read_text()
    assert pvd.count("<DataSet") == len(snaps)
    last = snaps[-1]
    mesh = meshio.read(finished / "vtu" / f"particles_{last['step']:08d}.vtu")
    order = np.argsort(mesh.point_data["id"])
    assert np.array_equal(mesh.points[order, :2], last["x"])
    assert np.array_equal(mesh.point_data["p"][order], last["p"])
    assert np.array_equal(mesh.point_data["stress"][order], last["stress"])


def test_export_xdmf_rewrites_the_sidecar(finished):
    (finished / "particles.xdmf").unlink()
    r = cli("export", str(finished), "--format", "xdmf")
    assert r.returncode == 0, r.stderr
    text = (finished / "particles.xdmf").read_text()
    assert text.count("<Grid Name=") == len(read_snapshots(finished / "particles.h5")) + 1

"""Removal of a region at a given time (the gate of a collapse, an excavated toe): the
particles inside leave the run, the census follows, and a restart across it continues
the same run."""

import shutil

import numpy as np

from psph.app.run import run
from psph.config.load import load_scene
from psph.io.checkpoint import read_checkpoint
from psph.io.snapshots import read_snapshots
from tests.helpers import compare_runs, falling_far

# the top quarter of the block (a box) and a triangle at its lower right corner
REMOVE = ["remove=[{at = 0.05, min = [0.0, 1.15], max = [0.3, 1.3]}, "
          "{at = 0.1, polygon = [[0.2, 0.0], [0.3, 0.0], [0.3, 2.0]]}]"]


def test_regions_are_removed_at_their_times(tmp_path):
    from mpi4py import MPI

    scene = load_scene(str(falling_far(tmp_path)), REMOVE + ["time.end=0.15"])
    summary = run(scene, tmp_path / "out", comm=MPI.COMM_SELF, quiet=True)
    snaps = read_snapshots(tmp_path / "out" / "particles.h5")
    n0 = len(snaps[0]["id"])
    by_time = {round(s["time"], 3): s for s in snaps}
    assert len(by_time[0.05]["id"]) == n0  # the first removal acts on the next step
    after = by_time[0.1]
    y0 = after["x"][:, 1] - after["u"][:, 1]
    assert not np.any(y0 > 1.15 + 0.05)  # the top quarter is gone (it had fallen ~1 cm)
    assert 0 < len(after["id"]) < n0
    last = snaps[-1]
    assert len(last["id"]) < len(after["id"])  # the triangle went at 0.1 s
    assert summary["particles"] == len(last["id"])
    assert np.all(np.diff(last["id"]) > 0)


def test_restart_across_a_removal_is_bitwise(tmp_path):
    from mpi4py import MPI

    scene = load_scene(str(falling_far(tmp_path)),
                       REMOVE + ["time.end=0.15", "checkpoint.every=3500",
                                 "checkpoint.at_end=false"])
    run(scene, tmp_path / "full", comm=MPI.COMM_SELF, quiet=True)
    meta, state = read_checkpoint(tmp_path / "full" / "checkpoint.h5")
    assert meta["removals_done"] == 1 and meta["n_removed"] > 0  # between the two
    assert len(state["removed_ids"]) == meta["n_removed"] == meta["n_ids"] - len(state["key"])
    shutil.copytree(tmp_path / "full", tmp_path / "again")
    shutil.copytree(tmp_path / "full", tmp_path / "old")
    _as_older_checkpoint(tmp_path / "old" / "checkpoint.h5")
    for name in ("again", "old"):
        run(scene, tmp_path / name, comm=MPI.COMM_SELF, quiet=True,
            restart=tmp_path / name / "checkpoint.h5")
        assert compare_runs(tmp_path / "full" / "particles.h5",
                            tmp_path / name / "particles.h5") is None, name


def _as_older_checkpoint(path) -> None:
    """Rewrite a checkpoint as psph wrote it before issue 15: the `alive` mask (one uint8
    per id) instead of `removed_ids`, and no `n_removed` in meta."""
    import json

    import h5py

    with h5py.File(path, "r+") as f:
        meta = json.loads(f.attrs["meta"])
        alive = np.ones(meta.pop("n_removed") + meta["n_global"], np.uint8)
        alive[f["removed_ids"][()]] = 0
        del f["removed_ids"]
        f["alive"] = alive
        f.attrs["meta"] = json.dumps(meta)

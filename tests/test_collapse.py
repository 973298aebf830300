"""The dry column collapse (built-in `collapse_dry`, Drucker-Prager with softening and
artificial stress) on a short window: it starts at the toe, keeps the far side at rest,
stays finite, and reports its metrics."""

import json

import numpy as np
import pytest

from psph.io.snapshots import read_snapshots
from psph.run import run
from psph.scene import load_scene


@pytest.fixture(scope="module")
def collapse(tmp_path_factory):
    from mpi4py import MPI

    out = tmp_path_factory.mktemp("collapse")
    scene = load_scene("collapse_dry", ["time.end=0.3"])
    run(scene, out, comm=MPI.COMM_SELF, quiet=True)
    return out


def test_collapse_starts_at_the_toe_and_stays_finite(collapse):
    last = read_snapshots(collapse / "particles.h5")[-1]
    for f in ("x", "v", "stress", "eps_p"):
        assert np.all(np.isfinite(last[f])), f
    x0 = last["x"] - last["u"]
    yielded = last["eps_p"] > 1e-3
    assert yielded.sum() > 100
    # the failure wedge is on the free (right) side; the far side has not moved
    assert np.median(x0[yielded, 0]) > 2.5
    far = x0[:, 0] < 0.5
    assert np.max(np.abs(last["u"][far])) < 2e-3  # m
    assert last["x"][:, 0].max() > 4.0  # the toe has advanced


def test_collapse_metrics_in_summary(collapse):
    m = json.loads((collapse / "summary.json").read_text())["metrics"]["collapse"]
    assert m["runout_m"] > 0.0
    assert m["initial_height_m"] == pytest.approx(2.0)
    assert 1.9 < m["final_height_m"] <= 2.0 + 1e-6
    assert 0.0 < m["back_scarp_m"] <= m["toe_m"] + 0.1

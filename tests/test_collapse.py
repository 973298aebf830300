"""The dry column collapse (built-in `collapse_dry`, Drucker-Prager with softening and
artificial stress) on a short window: it starts at the toe, keeps the far side at rest,
stays finite, and reports its metrics."""

import json

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.io.snapshots import read_snapshots


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


def test_collapse_metric_series_in_summary(collapse):
    """`metrics.collapse.series` (issue 17, item 2): one entry a snapshot; the dissipated
    plastic work sum_i w_i V_i never decreases and ends at the top-level value, as the
    run-out series at the last snapshot's `runout_m`; the run-out's percentile spread and
    the slide times' resolution (the snapshot interval) are reported."""
    m = json.loads((collapse / "summary.json").read_text())["metrics"]["collapse"]
    series = m["series"]
    snaps = read_snapshots(collapse / "particles.h5")
    assert {len(v) for v in series.values()} == {len(snaps)}
    assert series["time_s"] == [s["time"] for s in snaps]
    work = np.array(series["plastic_work_J_per_m"])
    assert work[0] == 0.0 and work[-1] > 0.0 and np.all(np.diff(work) >= 0.0)
    last = snaps[-1]
    assert work[-1] == pytest.approx(np.sum(last["plastic_work"] * last["vol"]), rel=1e-12)
    assert m["plastic_work_J_per_m"] == work[-1]
    assert series["runout_m"][-1] == m["runout_m"] and series["toe_m"][-1] == m["toe_m"]
    assert series["back_scarp_m"][-1] == m["back_scarp_m"]
    assert 0.0 <= m["runout_spread_m"] < 0.5 * m["toe_m"]
    assert m["slide_time_resolution_s"] == pytest.approx(0.1, rel=1e-3)
    assert "excess_p_peak_Pa" not in m  # a dry run has no pore pressure
    # where the particles yielded they dissipated work, elsewhere none
    assert np.all((last["plastic_work"] > 0.0) == (last["eps_p"] > 0.0))

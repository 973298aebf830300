"""The 3D slope (issue 38): a `[[remove]]` polygon in plan with a depth, the plan's
metrics of `psph/verify/slope_3d.py`, and the built-in `slope_3d` through a short window
(bench/verification/slope_3d.py runs it and its plane-strain check in full)."""

import numpy as np
import pytest

from psph.app.run import run
from psph.config.schema import Removal
from psph.geometry.lattice import SerialReducer
from psph.geometry.shapes import removal_region
from psph.io.snapshots import read_snapshots
from tests.helpers import assert_bad_input
from tests.test_bad_input import run_cli

# slope_3d coarsened for CI: dx = 2 m, 16 m of the valley's half width, 0.1 s of gravity
# loading and 0.1 s after the cut
SHORT = ["particles.dx=2.0", "domain.max=[1000.0, 16.0, 40.0]", "initial.equilibrate=0.1",
         "time.end=0.1", "output.interval=0.05"]


def _lattice(dx: float = 1.0):
    """Points of a 6 x 4 column lattice in plan under a ground z = 10 - x (x, y, z on a
    dx lattice, z from dx / 2)."""
    c = (np.arange(6) + 0.5) * dx
    pts = [(x, y, z) for x in c for y in c[:4] for z in np.arange(0.5 * dx, 10.0 - x, dx)]
    return np.array(pts)


def test_a_plan_polygon_takes_whole_columns_or_the_depth_below_each_columns_top():
    x = _lattice()
    poly = [[2.0, 0.0], [6.0, 0.0], [6.0, 2.0], [2.0, 2.0]]
    inside_plan = (x[:, 0] > 2.0) & (x[:, 1] < 2.0)
    whole = removal_region(x, Removal(polygon=poly), 1.0, SerialReducer())
    assert np.array_equal(whole, inside_plan)
    cut = removal_region(x, Removal(polygon=poly, depth=2.0), 1.0, SerialReducer())
    col_top = np.array([x[(x[:, 0] == a) & (x[:, 1] == b), 2].max() for a, b in x[:, :2]])
    assert np.array_equal(cut, inside_plan & (x[:, 2] >= col_top - 2.0))
    assert cut.sum() == 8 * 3  # eight columns, each its top point and two below it
    box = Removal(min=[0.0, 0.0, 0.0], max=[1.0, 4.0, 2.0])
    assert np.array_equal(removal_region(x, box, 1.0, SerialReducer()),
                          (x[:, 0] <= 1.0) & (x[:, 2] <= 2.0))


def test_plan_metrics_count_the_scarp_rows_the_footprint_and_the_debris_volume():
    from mpi4py import MPI

    from psph.config.load import load_scene
    from psph.verify.slope_3d import plan_metrics

    scene = load_scene("slope_3d", ["domain.max=[20.0, 8.0, 40.0]"])
    dx = scene.particles.dx
    g = (np.arange(8) + 0.5) * dx
    x0 = np.array([(a, b, c) for a in g[:6] for b in g for c in (np.arange(20) + 0.5) * dx])
    x = x0.copy()
    # the scarp: the top 4 m of the columns at x < 4, y < 4 (two 2 dx rows) are gone ...
    gone = (x0[:, 0] < 4.0) & (x0[:, 1] < 4.0) & (x0[:, 2] > 16.0)
    # ... to x = 15.5, y as before, z = 0.5 + a metre each
    x[gone, 0] = 15.5
    x[gone, 2] = 0.5 + np.arange(gone.sum()) % 4
    u = x - x0
    vol = np.full(len(x), dx ** 3)
    m = plan_metrics(x, u, vol, scene, 20.0, MPI.COMM_SELF)
    # mirrored (the front is a symmetry plane): twice the model's
    assert m["scarp_width_m"] == 2 * 4.0
    cols = {(a, b) for a, b in x[gone, :2]}
    assert m["footprint_area_m2"] == 2 * len(cols) * dx * dx
    assert m["debris_volume_m3"] == 2 * gone.sum() * dx ** 3


def test_slope_3d_cuts_the_toe_in_plan_and_reports_the_section_and_the_plan(tmp_path):
    """The built-in scene, coarsened, through the gravity loading, the cut and 0.1 s:
    the toe is gone under the cut's polygon only, the centre line's metrics are those of
    the 2D scene (the initial back scarp at its crest), the plan's block is there, and
    `psph plot` draws the section, plan and perspective views, the centre line's frames
    and the plan's frames."""
    from mpi4py import MPI

    from psph.config.load import load_scene

    scene = load_scene("slope_3d", SHORT)
    summary = run(scene, tmp_path / "out", comm=MPI.COMM_SELF, quiet=True)
    snaps = read_snapshots(tmp_path / "out" / "particles.h5")
    x0 = snaps[0]["x"]
    assert np.any((x0[:, 0] > 160.0) & (x0[:, 1] < 12.5))  # the cut acts on the first step
    x0 = snaps[1]["x"] - snaps[1]["u"]
    toe = x0[:, 0] > 160.0
    assert toe.any() and np.all(x0[toe, 1] > 12.5)  # beside the cut only
    assert 170.0 < x0[:, 0].max() < 180.0  # the slope's toe beside it
    m = summary["metrics"]
    assert 140.0 <= m["collapse"]["back_scarp_m"] <= 145.0  # the crest, 140.749 m
    assert abs(m["collapse"]["initial_height_m"] - 20.0) <= 1.0
    plan = m["slope_3d"]
    assert plan["mirrored"] and plan["section_y_m"] == [0.0, 4.0]
    assert plan["series"]["time_s"] == m["collapse"]["series"]["time_s"]
    assert plan["retrogression_m"] == 0.0 and plan["scarp_width_m"] == 0.0
    assert m["pressure_quality"]["over_run"]["abs_excess_p99_max_Pa"] > 0.0
    from psph.analysis.plot import plot_run

    names = {p.name for p in plot_run(tmp_path / "out")}  # the centre section's frames
    assert {"slope_3d.png", "plan_frames.png", "section_p.png", "plan.png",
            "perspective_p.png"} <= names


@pytest.mark.parametrize("setting, words", [
    ("remove=[{at = 0.0, polygon = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], depth = 1.0}]",
     ["remove[0].depth", "1.0", "only with a polygon in plan in a 3D scene"]),
])
def test_a_depth_in_a_2d_scene_is_bad_input(tmp_path, setting, words):
    out = tmp_path / "out"
    r = run_cli("run", "terzaghi_tpi", "--out", str(out), "--set", setting)
    assert_bad_input(r, words, out)


def test_a_depth_with_a_box_is_bad_input(tmp_path):
    out = tmp_path / "out"
    r = run_cli("run", "slope_3d", "--out", str(out), "--set",
                "remove=[{at = 0.0, min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0], "
                "depth = 1.0}]")
    assert_bad_input(r, ["remove[0].depth", "only with a polygon in plan"], out)


def test_the_scarp_width_stops_at_the_domains_side():
    """A scarp across the whole of a 5 m wide half model: its 2 dx rows are cut at the
    side wall, the valley's width twice the model's 5 m."""
    from mpi4py import MPI

    from psph.config.load import load_scene
    from psph.verify.slope_3d import plan_metrics

    scene = load_scene("slope_3d", ["domain.max=[20.0, 5.0, 40.0]"])
    g = np.arange(5) + 0.5
    x0 = np.array([(a, b, c) for a in g for b in g for c in np.arange(20) + 0.5])
    x = x0.copy()
    x[(x0[:, 0] < 2.0) & (x0[:, 2] > 16.0), 0] += 12.0  # the top of the first two rows
    m = plan_metrics(x, x - x0, np.ones(len(x)), scene, 20.0, MPI.COMM_SELF)
    assert m["scarp_width_m"] == 2 * 5.0

"""Scenes in three dimensions (issue 37): the schema's dimension rules, the 3D lattice,
and the Section 4.1 column between four slip walls against Terzaghi's solution."""

import json

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.geometry.lattice import census, seed
from psph.physics.initial import initial_particles
from tests.test_bad_input import run_cli

# the CI-sized column: dx = 0.02 m (4 x 4 x 50 particles), to T_v = 0.1
SMALL = ["particles.dx=0.02", "domain.max=[0.08, 0.08, 1.0]",
         "particles.blocks=[{min=[0.0, 0.0, 0.0], max=[0.08, 0.08, 1.0]}]",
         "verification.tv=[0.05, 0.1]"]


@pytest.mark.parametrize("override, words", [
    (["--set", "gravity=[0.0, -9.81]"], ["gravity", "3 components", "dim = 3"]),
    (["--set", "particles.blocks=[{min=[0.0, 0.0], max=[0.04, 0.04]}]"],
     ["particles.blocks[0].min", "3 components"]),
    (["--set", "dim=2"], ["domain.min", "2 components"]),
    (["--set", "particles.polygons=[{vertices=[[0, 0], [0.04, 0], [0.04, 0.5]]}]"],
     ["particles.polygons", "2D only"]),
    (["--set", "decomposition.axis='w'"], ["decomposition.axis"]),
])
def test_a_vector_of_the_wrong_dimension_is_exit_2(override, words):
    r = run_cli("validate", "terzaghi_3d", *override)
    assert r.returncode == 2, r.stderr
    line = r.stderr.strip()
    assert "\n" not in line and "Traceback" not in line
    for w in words:
        assert w in line, line


def test_a_slab_collapse_must_fill_its_slab():
    """A 3D collapse read as plane strain must fill the domain between its front and back
    walls: a block narrower than that spreads in y and is not a plane-strain state."""
    r = run_cli("validate", "collapse_saturated_3d", "--set",
                "particles.blocks=[{min=[0.0, 0.04, 0.0], max=[4.0, 0.12, 2.0]}]")
    assert r.returncode == 2 and "\n" not in r.stderr.strip()
    for w in ("particles.blocks[0]", "plane-strain slab", "y from 0 to 0.16"):
        assert w in r.stderr, r.stderr


def test_a_2d_scene_refuses_3d_keys():
    for override, word in ((["--set", "boundaries.front={motion='slip'}"], "boundaries.front"),
                           (["--set", "gravity=[0.0, 0.0, -9.81]"], "gravity"),
                           (["--set", "decomposition.axis='z'"], "decomposition.axis")):
        r = run_cli("validate", "terzaghi", *override)
        assert r.returncode == 2 and word in r.stderr and "\n" not in r.stderr.strip()


def test_dim_follows_the_domain_corner(tmp_path):
    text = (load_scene("terzaghi_3d").model_dump_json())
    data = json.loads(text)
    del data["dim"]
    from psph.config.schema import Scene
    assert Scene.model_validate(data).dim == 3


def test_3d_lattice_ids_slabs_and_census():
    """A box block seeds dx^3 particles on its lattice, ids 0..n-1 with x fastest, then y,
    then z; any slab along any axis holds exactly the particles of its coordinates, with
    the same ids; the census counts them."""
    scene = load_scene("terzaghi_3d", ["particles.dx=0.02",
                                       "domain.max=[0.08, 0.06, 1.0]",
                                       "particles.blocks=[{min=[0.0, 0.0, 0.0], "
                                       "max=[0.08, 0.06, 1.0]}]"])
    x, key = seed(scene)
    assert x.shape == (4 * 3 * 50, 3) and np.array_equal(key, np.arange(600))
    assert np.allclose(x[1] - x[0], [0.02, 0, 0]) and np.allclose(x[4] - x[0], [0, 0.02, 0])
    assert np.allclose(x[12] - x[0], [0, 0, 0.02])
    for axis in range(3):
        lo, hi = 0.02, 0.05
        xs, ks = seed(scene, axis, lo, hi)
        inside = (x[:, axis] >= lo) & (x[:, axis] < hi)
        assert np.array_equal(ks, key[inside]) and np.array_equal(xs, x[inside])
        values, counts = census(scene, axis)
        for v, c in zip(values, counts, strict=True):
            assert c == np.sum(x[:, axis] == v)
    data = initial_particles(scene)
    assert np.allclose(data["vol"], 0.02 ** 3)
    top = data["load_index"] == 0
    assert top.sum() == 12 and np.allclose(data["traction"][top], [0, 0, -0.02 ** 2])
    assert np.all(x[top, 2] > 0.97)


@pytest.fixture(scope="module")
def small_column(tmp_path_factory):
    out = tmp_path_factory.mktemp("terzaghi_3d") / "out"
    return out, run(load_scene("terzaghi_3d", SMALL), out, quiet=True)


def test_terzaghi_3d_column_within_half_a_percent(small_column):
    """The Section 4.1 column in 3D, laterally confined by four slip walls (CI size, dx =
    0.02 m): max |p - p_a| / q within 0.5 % at T_v = 0.05 and 0.1 (0.26 and 0.14 %; the
    issue asks 1 % of the CI column; with the global damping it was 0.39 and 0.29 %. The
    full column: `mpirun -n 2 .venv/bin/python -m psph run terzaghi_3d`)."""
    _, summary = small_column
    errors = summary["errors"]["pressure"]
    assert set(errors) == {"0.05", "0.1"}
    for tv, e in errors.items():
        assert e["max_abs_p_error_over_q"] < 0.005, (tv, e)
    assert summary["pressure_solve"]["steps_not_converged"] == 0


def test_paraview_reader_opens_the_3d_run(small_column):
    """VTK's XDMF reader (ParaView's) opens particles.xdmf of a 3D run: every snapshot a
    time step, 3D points within the column, p and the 6-component stress."""
    import vtk

    out, summary = small_column
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(out / "particles.xdmf"))
    reader.UpdateInformation()
    times = reader.GetOutputInformation(0).Get(vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    assert len(times) == 3 and times[0] == 0.0
    reader.UpdateTimeStep(times[-1])
    grid = reader.GetOutputDataObject(0)
    assert grid.GetNumberOfPoints() == summary["particles"] == 800
    x0, x1, y0, y1, z0, z1 = grid.GetBounds()
    assert 0 < x0 < x1 < 0.08 and 0 < y0 < y1 < 0.08 and 0.0 < z0 < 0.02 and 0.95 < z1 < 1.0
    assert grid.GetPointData().GetArray("p").GetNumberOfComponents() == 1
    assert grid.GetPointData().GetArray("stress").GetNumberOfTuples() == 800


def test_plot_draws_section_plan_and_perspective(small_column):
    out, _ = small_column
    r = run_cli("plot", str(out))
    assert r.returncode == 0, r.stderr
    for name in ("section_p.png", "plan.png", "perspective_p.png", "terzaghi.png"):
        assert (out / name).stat().st_size > 10_000, name


def _cube_surface(path, lo=0.1, hi=0.5, drop=0):
    """A closed cube surface [lo, hi]^3 as 12 triangles (`drop` of them left out)."""
    import meshio

    v = np.array([[x, y, z] for z in (lo, hi) for y in (lo, hi) for x in (lo, hi)], float)
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2],
             [1, 3, 7, 5]]
    tri = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    meshio.write(path, meshio.Mesh(v, [("triangle", np.array(tri[drop:]))]))
    return path


def _sphere_surface(path, centre, radius, n=48):
    """A closed latitude-longitude sphere surface of quads (triangles at the poles)."""
    import meshio

    th = np.linspace(0, np.pi, n // 2 + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.array([[np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)]
                     for t in th for p in ph])
    pts = np.vstack([[0, 0, 1], ring, [0, 0, -1]]) * radius + centre
    m, last = len(ph), len(pts) - 1
    tri = [[0, 1 + i, 1 + (i + 1) % m] for i in range(m)]
    for r in range(len(th) - 1):
        a, b = 1 + r * m, 1 + (r + 1) * m
        for i in range(m):
            j = (i + 1) % m
            tri += [[a + i, b + i, b + j], [a + i, b + j, a + j]]
    a = 1 + (len(th) - 1) * m
    tri += [[a + i, last, a + (i + 1) % m] for i in range(m)]
    meshio.write(path, meshio.Mesh(pts, [("triangle", np.array(tri))]))
    return path


def test_volumes_from_closed_surface_meshes(tmp_path):
    """A closed surface (STL) fills the domain lattice points inside it: a cube exactly,
    a sphere to within its faceting; ids in lattice order on any slab."""
    from psph.geometry.solids import inside_surface, read_surface

    pts, tri = read_surface(str(_cube_surface(tmp_path / "cube.stl")), "k")
    xs = (np.arange(20) + 0.5) * 0.05
    assert inside_surface(xs, xs, xs, pts, tri, 0.05).sum() == 8 ** 3
    sphere = _sphere_surface(str(tmp_path / "sphere.stl"), [0.5, 0.5, 0.5], 0.4)
    scene = load_scene("terzaghi_3d", [
        "domain.max=[1.0, 1.0, 1.0]", "particles.dx=0.04", "particles.blocks=[]",
        f"particles.meshes=[{{file='{sphere}'}}]", "loads=[]",
        "verification.reference='none'", "time.end=0.01"])
    x, key = seed(scene)
    volume = len(x) * 0.04 ** 3
    assert abs(volume / (4 / 3 * np.pi * 0.4 ** 3) - 1) < 0.03
    assert np.all(np.linalg.norm(x - 0.5, axis=1) < 0.4 + 1e-9)
    assert np.array_equal(key, np.arange(len(x)))
    xs_, ks = seed(scene, 1, 0.3, 0.6)
    inside = (x[:, 1] >= 0.3) & (x[:, 1] < 0.6)
    assert np.array_equal(ks, key[inside]) and np.array_equal(xs_, x[inside])
    values, counts = census(scene, 2)
    assert counts.sum() == len(x)


def test_an_open_surface_where_a_volume_is_asked_is_exit_2(tmp_path):
    stl = _cube_surface(str(tmp_path / "open.stl"), drop=1)
    r = run_cli("validate", "terzaghi_3d", "--set", f"particles.meshes=[{{file='{stl}'}}]")
    line = r.stderr.strip()
    assert r.returncode == 2 and "\n" not in line, line
    assert "particles.meshes[0].file" in line and "not closed" in line


def test_surface_load_faces_close_the_ball():
    """`loads.side = "surface"` (physics.initial.exposed_faces): a sphere octant between
    three slip walls. Each exposed lattice face carries -n dx^2; the faces against the
    walls carry nothing, so the tractions add to minus the walls' faces: -dx^2 times the
    particles of the layer next to each wall, along that wall's normal (the union of
    the particles' cells is closed). Only surface particles are loaded, none inside."""
    scene = load_scene("cryer", ["particles.dx=0.1"])
    data = initial_particles(scene)
    x, tr = data["x"], data["traction"]
    dx = 0.1
    for d in range(3):
        next_to_wall = np.sum(x[:, d] < dx)
        assert np.isclose(tr[:, d].sum(), -next_to_wall * dx * dx, rtol=0, atol=1e-12)
    loaded = data["load_index"] == 0
    r = np.linalg.norm(x, axis=1)
    assert np.all(r[loaded] > 1.0 - 2 * dx) and np.all(r[~loaded] < 1.0 - 0.3 * dx)
    assert np.all(np.einsum("ij,ij->i", tr[loaded], x[loaded]) < 0)  # inward


def test_cryer_sphere_mandel_cryer_peak(tmp_path):
    """Cryer's sphere (scene `cryer` at its dx = 0.05 m, 4,194 particles in the octant, the
    load ramped over 10 ms rather than 2 ms: the ramp's elastic wave is smaller) to
    t = 0.25 s: the centre's pressure rises above p0 and peaks within 5 % of the series'
    peak and 10 % of its time (issue 37). At dx = 0.1 m the peak comes 22 % early: the 3D
    free-surface test (kernels/free_surface.py) drains 121 of the 528 particles, down to
    0.79 dx inside the sphere's surface, where the trace test before 2026-12-06 drained
    112, down to 0.69 dx (docs/vv/cryer.md)."""
    scene = load_scene("cryer", ["time.end=0.25", "loads.0.ramp=0.01"])
    e = run(scene, tmp_path / "out", quiet=True)["errors"]
    assert e["reference_peak_over_p0"] > 1.3 and e["peak_over_p0"] > 1.2
    assert abs(e["peak_error"]) < 0.05 and abs(e["peak_time_error"]) < 0.10, e


def test_cryer_run_ended_within_the_ramp_says_so(tmp_path):
    """A `cryer` run stopped before its load's ramp ends has no peak to compare: its
    summary says so instead of failing (it raised on an empty argmax)."""
    scene = load_scene("cryer", ["particles.dx=0.1", "time.end=0.001", "loads.0.ramp=0.01",
                                 "output.probes={centre=[0.05, 0.05, 0.05]}"])
    s = run(scene, tmp_path / "out", quiet=True)
    assert s["status"] == "finished" and "ramp" in s["errors"]["note"]


def test_spheres_are_3d_only():
    r = run_cli("validate", "terzaghi", "--set",
                "particles.spheres=[{centre=[0.0, 0.0], radius=0.1}]")
    assert r.returncode == 2 and "particles.spheres" in r.stderr and "3D only" in r.stderr


def test_radial_collapse_metrics_and_lube_law():
    """`verify.collapse_3d`: the run-out radius is the 99.8th percentile of the distance
    from the axis, the final height the top near the axis; Lube et al.'s law at both
    branches."""
    from psph.verify.collapse_3d import lube_runout, radial_metrics

    rng = np.random.default_rng(0)
    r = np.sqrt(rng.random(20000)) * 2.0  # a uniform disc of radius 2
    th = rng.random(20000) * np.pi / 2
    z = 0.3 * (1 - r / 2)  # a cone 0.3 high
    x = np.column_stack([r * np.cos(th), r * np.sin(th), z])
    m = radial_metrics(x, (0.0, 0.0), 0.05)
    assert abs(m["runout_radius_m"] - np.percentile(r, 99.8)) < 1e-12
    assert abs(m["final_height_m"] - (z[r < 0.1].max() + 0.025)) < 1e-12
    assert lube_runout(0.5) == pytest.approx(0.62) and lube_runout(4.0) == pytest.approx(3.2)


def test_collapse_3d_quarter_column_spreads_and_stops(tmp_path):
    """The quarter cylinder of `collapse_3d` (CI size: dx = 0.1 m, 1 s): it spreads
    radially and sinks, every particle stays on the floor's side and inside the
    quarter, summary.json carries Lube et al.'s comparison, and its front stops: the
    run-out radius grows by less than 0.1 m over the last 0.25 s (on the plane-strain
    cone with the plain strain rate it grew 0.06 m, and without the floor's
    `weight_friction` a film at the Drucker-Prager apex ran on, 0.40 m, to 1.17 r_i at
    1 s: docs/vv/collapse_3d.md)."""
    scene = load_scene("collapse_3d", ["particles.dx=0.1", "time.end=1.0",
                                       "output.interval=0.25"])
    s = run(scene, tmp_path / "out", quiet=True)
    c = s["errors"]["collapse_3d"]
    assert c["aspect_ratio"] == 0.5 and c["lube_runout_normalised"] == pytest.approx(0.62)
    assert c["runout_normalised"] > 0.05 and c["final_height_m"] < 0.5
    radius = c["series"]["runout_radius_m"]
    assert len(radius) == 5 and radius[-1] - radius[-2] < 0.1, radius
    from psph.io.snapshots import read_snapshots

    last = read_snapshots(tmp_path / "out" / "particles.h5")[-1]
    assert len(last["id"]) == s["particles"] and last["x"].min() > 0.0


@pytest.mark.slow
def test_collapse_3d_runout_within_10_percent_of_lube_at_a_half(tmp_path):
    """`collapse_3d` at its own resolution (dx = 0.05 m, a = 0.5), to 1.25 s: the front
    has stopped (it stops by 1 s: docs/vv/collapse_3d.md) and the run-out is within 10 %
    of Lube et al.'s 1.24 a (measured 0.644, +3.9 %; the plane-strain cone and the plain
    strain rate gave +15.7 %), the top left at its height as Lube's below a = 0.74."""
    scene = load_scene("collapse_3d", ["time.end=1.25", "output.interval=0.25"])
    c = run(scene, tmp_path / "out", quiet=True)["errors"]["collapse_3d"]
    radius = c["series"]["runout_radius_m"]
    assert radius[-1] - radius[-2] < 0.005, radius
    assert abs(c["runout_error"]) < 0.10, c["runout_normalised"]
    assert c["published_height_over_initial_radius"] == 0.5  # a = 0.5, below 0.74
    assert c["final_height_over_initial_radius"] == pytest.approx(
        c["published_height_over_initial_radius"], abs=0.05)


def test_export_vtu_of_a_3d_run(small_column):
    """`psph export --format vtu` of a 3D run: one VTU a snapshot with 3D points, the
    6-component stress and the 3-component u, v (meshio reads them back)."""
    import meshio

    out, summary = small_column
    r = run_cli("export", str(out), "--format", "vtu")
    assert r.returncode == 0, r.stderr
    files = sorted((out / "vtu").glob("*.vtu"))
    assert len(files) == 3
    mesh = meshio.read(files[-1])
    assert mesh.points.shape == (summary["particles"], 3)
    assert mesh.point_data["stress"].shape == (800, 6) and mesh.point_data["u"].shape == (800, 3)


def test_saturated_slab_is_the_2d_collapse_extruded(tmp_path):
    """`collapse_saturated_3d` (CI size: dx = 0.08 m, 4 particles thick, 0.01 s): between
    free-slip walls the slab's mirror ghosts continue the lattice, so every one of its
    four y-layers carries the same x-z field (p, u, stress) to round-off: the plane-strain
    state of the 2D scene, through which its metrics are read (`plane_strain_view`: the
    same initial height as the 2D scene's, no checkerboard index). How close it comes to
    the 2D scene is the full runs' question (bench/verification/collapse_saturated_3d.py):
    in these first 0.01 s both are in the transient of the released face, which TPI
    carries one kernel support a step, and the 3D spline summed across the slab is not
    the 2D spline."""
    from psph.io.snapshots import read_snapshots

    common = ["particles.dx=0.08", "time.end=0.01", "output.interval=0.01"]
    s3 = run(load_scene("collapse_saturated_3d", common + [
        "domain.max=[12.0, 0.32, 3.0]",
        "particles.blocks=[{min=[0.0, 0.0, 0.0], max=[4.0, 0.32, 2.0]}]"]),
        tmp_path / "3d", quiet=True)
    s2 = run(load_scene("collapse_saturated_psi0", common), tmp_path / "2d", quiet=True)
    m3, m2 = s3["metrics"]["collapse"], s2["metrics"]["collapse"]
    assert m3["initial_height_m"] == pytest.approx(m2["initial_height_m"], abs=1e-12)
    assert m3["runout_m"] > 0.0 and m2["runout_m"] > 0.0
    assert s3["metrics"]["pressure_quality"]["over_run"]["checkerboard_p_all_max"] is None
    n_2d = s2["particles"]
    b = read_snapshots(tmp_path / "3d" / "particles.h5")[-1]
    x0 = b["x"] - b["u"]
    layer = np.round(x0[:, 1] / 0.08 - 0.5).astype(int)
    assert sorted(set(layer)) == [0, 1, 2, 3]
    site = np.round(x0[:, [0, 2]] / 0.04).astype(int)
    by_site = {}
    for i, k in enumerate(map(tuple, site)):
        by_site.setdefault(k, []).append(i)
    groups = np.array([sorted(g, key=lambda i: layer[i]) for g in by_site.values()])
    assert groups.shape == (n_2d, 4)
    for name, scale in (("p", np.abs(b["p"]).max()), ("u", np.abs(b["u"]).max()),
                        ("stress", np.abs(b["stress"]).max())):
        f = b[name][groups]  # (sites, layers, ...)
        assert np.abs(f - f[:, :1]).max() <= 1e-9 * scale, name

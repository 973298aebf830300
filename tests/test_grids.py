"""Elevation grids in 3D scenes (issue 38): ESRI ASCII and x, y, z CSV grids, soil
layers between them, a water table and a bedrock surface from them, and their bad
input."""

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.geometry.grids import GridError, grid_triangles, read_grid
from psph.io.snapshots import read_snapshots
from psph.physics.initial import initial_particles
from tests.helpers import assert_bad_input
from tests.test_bad_input import run_cli

G, RHO_L = 9.81, 1000.0
DENSE = {"porosity": 0.35, "rho_s": 2650.0}
LIGHT = {"porosity": 0.5, "rho_s": 1800.0}
WATER_TABLE = 1.975


def write_asc(path, x0, y0, cell, z, corner=True, nodata=None):
    """An ESRI ASCII grid of z (ny, nx) whose row 0 is the southern one (written north
    first, as the format has it)."""
    ny, nx = z.shape
    key = "corner" if corner else "center"
    head = [f"ncols {nx}", f"nrows {ny}", f"xll{key} {x0}", f"yll{key} {y0}",
            f"cellsize {cell}"] + ([f"NODATA_value {nodata}"] if nodata is not None else [])
    rows = [" ".join(f"{v:.6f}" for v in z[j]) for j in range(ny - 1, -1, -1)]
    path.write_text("\n".join(head + rows) + "\n")
    return str(path)


def write_xyz(path, xs, ys, z):
    gx, gy = np.meshgrid(xs, ys)
    rows = ["x,y,z"] + [f"{a},{b},{c}" for a, b, c in zip(gx.ravel(), gy.ravel(), z.ravel(),
                                                            strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def test_an_asc_grid_puts_its_first_row_north_and_is_bilinear(tmp_path):
    xs, ys = np.arange(4) * 0.5, np.arange(3) * 0.5  # cell centres (xllcenter 0, 0)
    plane = 1.0 + 0.2 * xs[None, :] - 0.1 * ys[:, None]
    g = read_grid(write_asc(tmp_path / "p.asc", 0.0, 0.0, 0.5, plane, corner=False))
    assert np.allclose(g.x, xs) and np.allclose(g.y, ys)
    px, py = np.array([0.1, 1.3, 1.5]), np.array([0.9, 0.2, 1.0])
    assert np.allclose(g.at(px, py), 1.0 + 0.2 * px - 0.1 * py)  # a plane exactly
    assert np.isnan(g.at(np.array([1.6]), np.array([0.5]))[0])  # beyond the last node
    corner = read_grid(write_asc(tmp_path / "c.asc", -0.25, -0.25, 0.5, plane))
    assert np.allclose(corner.x, xs) and np.allclose(corner.y, ys)  # centres of cells
    csv = read_grid(write_xyz(tmp_path / "p.csv", xs, ys, plane))
    assert np.allclose(csv.z, g.z, rtol=0, atol=1e-6)  # the .asc holds 6 decimals


def test_a_node_next_to_a_hole_keeps_its_elevation_and_csv_coordinates_are_snapped(
        tmp_path):
    """On a node or an edge a corner of weight 0 does not count: a DEM with a NODATA
    margin still has data at its last nodes. CSV coordinates written with rounding noise
    (0.30000000000000004 beside 0.3) are one grid line."""
    z = np.array([[1.0, 2.0, -9999.0], [1.0, 2.0, -9999.0]])
    g = read_grid(write_asc(tmp_path / "m.asc", 0.0, 0.0, 1.0, z, corner=False,
                            nodata=-9999))
    assert g.at(np.array([1.0, 0.5]), np.array([0.5, 1.0])).tolist() == [2.0, 1.5]
    assert np.isnan(g.at(np.array([1.5]), np.array([0.5]))[0])
    rows = ["0.0,0.0,1", "0.1,0.0,1", "0.30000000000000004,0.0,1", "0.2,0.0,1",
            "0.0,1.0,2", "0.1,1.0,2", "0.3,1.0,2", "0.2,1.0,2"]
    (tmp_path / "n.csv").write_text("\n".join(rows) + "\n")
    g = read_grid(str(tmp_path / "n.csv"))
    assert g.z.shape == (2, 4) and np.allclose(g.x, [0.0, 0.1, 0.2, 0.3])


def test_sloped_layers_on_a_long_domain_hold_the_points_between_their_grids(tmp_path):
    """Grids that slope in x and y on a domain longer in x than in y (an .asc and a CSV):
    the seeded points are exactly the lattice points with bottom <= z <= top, counted
    directly, and the census agrees."""
    from psph.geometry.lattice import census, lattice_axes, seed

    xs, ys = np.linspace(-0.1, 1.3, 8), np.linspace(-0.1, 0.5, 4)
    gx, gy = np.meshgrid(xs, ys)
    top = 0.8 + 0.1 * gx - 0.2 * gy
    bottom = 0.1 + 0.05 * gx + 0.1 * gy
    t = write_asc(tmp_path / "t.asc", -0.1, -0.1, 0.2, top, corner=False)
    b = write_xyz(tmp_path / "b.csv", xs, ys, bottom)
    scene = load_scene("terzaghi_3d", [
        "domain.max=[1.2, 0.4, 1.0]", "particles.dx=0.05", "particles.blocks=[]",
        f"particles.layers=[{{top='{t}', bottom='{b}'}}]", "loads=[]",
        "verification.reference='none'", "time.end=0.01"])
    x, key = seed(scene)
    c = lattice_axes(scene.domain.min, scene.domain.max, 0.05)
    zz, yy, xx = np.meshgrid(c[2], c[1], c[0], indexing="ij")
    zt = 0.8 + 0.1 * xx - 0.2 * yy
    zb = 0.1 + 0.05 * xx + 0.1 * yy
    want = (zz >= zb - 1e-9) & (zz <= zt + 1e-9)
    assert len(x) == want.sum() and np.array_equal(key, np.arange(len(x)))
    assert np.all(x[:, 2] <= 0.8 + 0.1 * x[:, 0] - 0.2 * x[:, 1] + 1e-9)
    assert np.all(x[:, 2] >= 0.1 + 0.05 * x[:, 0] + 0.1 * x[:, 1] - 1e-9)
    assert census(scene, 0)[1].sum() == len(x)


def test_nodata_cells_have_no_surface_and_no_triangles(tmp_path):
    z = np.zeros((3, 3))
    z[1, 1] = -9999.0
    g = read_grid(write_asc(tmp_path / "h.asc", 0.0, 0.0, 1.0, z, corner=False,
                            nodata=-9999))
    assert np.isnan(g.at(np.array([0.5]), np.array([0.5]))[0])
    points, tri = grid_triangles(g)
    assert len(points) == 9 and len(tri) == 0  # every cell has the hole as a corner
    with pytest.raises(GridError, match="evenly spaced"):
        read_grid(write_xyz(tmp_path / "u.csv", np.array([0.0, 1.0, 3.0]),
                            np.array([0.0, 1.0]), np.zeros((2, 3))))


def _layered_scene(tmp_path, extra=()):
    """A 0.2 x 0.2 x 2 m column of two materials between three flat grids (z = 0, 1, 2;
    an .asc, a CSV and an .asc), a water table grid at 1.975 m: the 2D `two_layers`
    column (tests/test_materials.py) in 3D."""
    xs = np.linspace(-0.1, 0.3, 5)
    flat = np.ones((5, 5))
    files = {"base": write_asc(tmp_path / "base.asc", -0.1, -0.1, 0.1, 0.0 * flat,
                               corner=False),
             "mid": write_xyz(tmp_path / "mid.csv", xs, xs, 1.0 * flat),
             "ground": write_asc(tmp_path / "ground.asc", -0.1, -0.1, 0.1, 2.0 * flat,
                                 corner=False),
             "table": write_asc(tmp_path / "table.asc", -0.1, -0.1, 0.1, WATER_TABLE * flat,
                                corner=False)}
    text = f"""
name = "grid_layers"
gravity = [0.0, 0.0, -9.81]
[domain]
min = [0.0, 0.0, 0.0]
max = [0.2, 0.2, 2.0]
[particles]
dx = 0.05
[[particles.layers]]
top = "{files['mid']}"
bottom = "{files['base']}"
material = "dense"
[[particles.layers]]
top = "{files['ground']}"
bottom = "{files['mid']}"
material = "light"
[[materials]]
name = "dense"
E = 20.0e6
nu = 0.33
porosity = 0.35
rho_s = 2650.0
k = 2.0e-4
[[materials]]
name = "light"
E = 20.0e6
nu = 0.33
porosity = 0.5
rho_s = 1800.0
k = 2.0e-4
[boundaries]
left = {{ motion = "slip" }}
right = {{ motion = "slip" }}
front = {{ motion = "slip" }}
back = {{ motion = "slip" }}
bottom = {{ motion = "fixed" }}
top = {{ motion = "free", flow = "drained" }}
[initial]
water_table = "{files['table']}"
k0 = 0.5
[pressure]
scheme = "explicit"
drained_boundary = "layer"
[time]
end = 0.05
[output]
interval = 0.05
[stabilisation]
damping = 0.02
"""
    path = tmp_path / "grid_layers.toml"
    path.write_text(text)
    return load_scene(str(path), list(extra)), files


def _mixture(m):
    return (1 - m["porosity"]) * m["rho_s"] + m["porosity"] * RHO_L


def _reference(z):
    weight = np.where(z >= 1.0, _mixture(LIGHT) * (2.0 - z),
                      _mixture(LIGHT) * 1.0 + _mixture(DENSE) * (1.0 - z))
    p = RHO_L * G * np.maximum(WATER_TABLE - z, 0.0)
    return -G * weight + p, p


def test_layers_between_grids_take_their_materials_and_the_layered_overburden(tmp_path):
    scene, _ = _layered_scene(tmp_path)
    d = initial_particles(scene)
    z = d["x"][:, 2]
    assert len(z) == 4 * 4 * 40
    assert np.array_equal(d["material"], np.where(z > 1.0, 1.0, 0.0))
    sv_ref, p_ref = _reference(z)
    wet = z < WATER_TABLE - 1e-9
    assert np.allclose(d["p"][wet], p_ref[wet])
    assert np.max(np.abs(d["stress"][:, 2] - sv_ref)) < 1e-9 * np.max(np.abs(sv_ref))
    assert np.allclose(d["stress"][:, 0], 0.5 * d["stress"][:, 2])


def test_a_layered_grid_column_stays_at_its_overburden(tmp_path):
    """After 0.05 s at rest: p within 0.5 % and sigma'_v within 2 % of the layered
    overburden (of the base values), as the 2D column (tests/test_materials.py)."""
    scene, _ = _layered_scene(tmp_path)
    run(scene, tmp_path / "out", quiet=True)
    last = read_snapshots(tmp_path / "out" / "particles.h5")[-1]
    z = last["x"][:, 2] - last["u"][:, 2]
    sv_ref, p_ref = _reference(z)
    assert np.max(np.abs(last["p"] - p_ref)) < 0.005 * p_ref.max()
    assert np.max(np.abs(last["stress"][:, 2] - sv_ref)) < 0.02 * np.abs(sv_ref).max()
    assert np.max(np.abs(last["stress"][:, 0] - 0.5 * sv_ref)) < 0.02 * np.abs(sv_ref).max()


def test_a_bedrock_grid_lines_the_floor_as_inline_triangles_do(tmp_path):
    from psph.config.boundaries import Surface, triangles_of
    from psph.geometry.surfaces import surface_particles

    xs = np.linspace(-0.5, 1.5, 5)
    grid = write_xyz(tmp_path / "rock.csv", xs, xs, np.zeros((5, 5)))
    pts, tri = triangles_of(Surface(grid=grid, soil="above"))
    assert len(tri) == 2 * 4 * 4
    box = ([0.0, 0.0, 0.0], [-0.2, -0.2, -1.0], [1.2, 1.2, 1.0])
    a = surface_particles(pts, tri, "above", 0.1, 0.13, *box)
    b = surface_particles(np.array([[-0.5, -0.5, 0], [1.5, -0.5, 0], [1.5, 1.5, 0],
                                    [-0.5, 1.5, 0.0]]), np.array([[0, 1, 2], [0, 2, 3]]),
                          "above", 0.1, 0.13, *box)
    assert np.allclose(a[0], b[0]) and np.allclose(a[1], b[1])


@pytest.mark.parametrize("case, words", [
    ("hole", ["particles.layers[1].top", "ground.asc at row 2, column 2", "no data"]),
    ("short", ["particles.layers[1].top", "ground.asc", "outside the grid", "cover"]),
    ("cross", ["particles.layers[0].bottom", "base.asc", "above the top", "cross"]),
    ("profile", ["particles.layers[1].top", "elevation grids"]),
    ("table", ["initial.water_table", "table.asc", "outside the grid"]),
    ("dry", ["initial.water_table", "table.asc at row", "x = 0.025, y = 0.025",
             "0.05 m below the bedrock", "base.asc at row", "z = 0.1 m",
             "a saturated layer needs its water table above the bedrock"]),
    ("dry_level", ["initial.water_table = level", "x = 0.025, y = 0.025",
                   "0.05 m below the bedrock", "base.asc"]),
])
def test_bad_grids_exit_2_one_line_nothing_written(tmp_path, case, words):
    scene, files = _layered_scene(tmp_path)
    flat = np.ones((5, 5))
    if case == "hole":
        z = 2.0 * flat
        z[2, 2] = -9999.0
        write_asc(tmp_path / "ground.asc", -0.1, -0.1, 0.1, z, corner=False, nodata=-9999)
    elif case == "short":  # covers x up to 0.1 only
        write_asc(tmp_path / "ground.asc", -0.1, -0.1, 0.1, 2.0 * np.ones((5, 3)),
                  corner=False)
    elif case == "cross":
        write_asc(tmp_path / "base.asc", -0.1, -0.1, 0.1, 1.5 * flat, corner=False)
    elif case == "profile":
        (tmp_path / "ground.asc").unlink()
        text = (tmp_path / "grid_layers.toml").read_text().replace(
            f'top = "{files["ground"]}"', 'top = [[0.0, 2.0], [0.2, 2.0]]')
        (tmp_path / "grid_layers.toml").write_text(text)
    elif case == "table":
        write_asc(tmp_path / "table.asc", 0.5, 0.5, 0.1, WATER_TABLE * flat, corner=False)
    elif case in ("dry", "dry_level"):  # the bedrock raised to 0.1 m, the table at 0.05 m
        write_asc(tmp_path / "base.asc", -0.1, -0.1, 0.1, 0.1 * flat, corner=False)
        write_asc(tmp_path / "table.asc", -0.1, -0.1, 0.1, 0.05 * flat, corner=False)
        if case == "dry_level":
            text = (tmp_path / "grid_layers.toml").read_text().replace(
                f'water_table = "{files["table"]}"', "water_table = 0.05")
            (tmp_path / "grid_layers.toml").write_text(text)
    out = tmp_path / "out"
    r = run_cli("run", str(tmp_path / "grid_layers.toml"), "--out", str(out))
    assert_bad_input(r, words, out)


def test_data_files_beside_the_scene_are_found_from_anywhere(tmp_path, monkeypatch):
    """Grids named relative to the scene file are found when the run starts elsewhere
    (and stay as written when found from the working directory)."""
    scene_dir = tmp_path / "site"
    scene_dir.mkdir()
    _layered_scene(scene_dir)
    text = (scene_dir / "grid_layers.toml").read_text().replace(str(scene_dir) + "/", "")
    (scene_dir / "grid_layers.toml").write_text(text)
    assert '"ground.asc"' in text
    monkeypatch.chdir(tmp_path)
    scene = load_scene(str(scene_dir / "grid_layers.toml"))
    assert scene.particles.layers[1].top == str(scene_dir / "ground.asc")
    assert scene.initial.water_table == str(scene_dir / "table.asc")
    monkeypatch.chdir(scene_dir)
    assert load_scene("grid_layers.toml").particles.layers[1].top == "ground.asc"

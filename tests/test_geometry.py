"""Scene geometry: polygons and meshes (read by meshio) seed particles on the domain
lattice; a polygon and the mesh of the same shape give the same particles."""

import subprocess
import sys

import meshio
import numpy as np
import pytest

from psph.config.load import load_scene
from psph.physics.initial import soil_positions

SLOPE = [[0.0, 0.0], [3.0, 0.0], [3.0, 0.5], [2.0, 0.5], [1.0, 1.0], [0.0, 1.0]]


def _scene(tmp_path, geometry: str):
    f = tmp_path / "s.toml"
    f.write_text(f"""
name = "geo"
[domain]
min = [0.0, 0.0]
max = [4.0, 2.0]
[particles]
dx = 0.05
{geometry}
[material]
E = 1.0e7
nu = 0.3
porosity = 0.4
rho_s = 2000.0
k = 1.0e-4
[time]
end = 0.001
""")
    return load_scene(str(f))


def test_polygon_fills_its_area(tmp_path):
    scene = _scene(tmp_path, f"[[particles.polygons]]\nvertices = {SLOPE}")
    x = soil_positions(scene)
    area = 3.0 * 0.5 + 1.0 * 0.5 + 0.5 * 1.0 * 0.5  # 2.25 m^2
    assert abs(len(x) * 0.05**2 - area) / area < 0.02
    assert len(np.unique(np.round(x / 0.025).astype(int), axis=0)) == len(x)  # no doubles
    # the lattice is the domain's: centres at (i + 1/2) dx
    v = x / 0.05 - 0.5
    assert np.allclose(v, np.round(v), atol=1e-6)


def test_mesh_gives_the_polygon_particles(tmp_path):
    pts = np.array([[0, 0], [3, 0], [3, 0.5], [2, 0.5], [1, 1], [0, 1], [1, 0.5]], float)
    cells = [("triangle", np.array([[6, 3, 4]])),
             ("quad", np.array([[0, 1, 2, 3], [0, 3, 6, 5]])),
             ("triangle", np.array([[6, 4, 5]]))]
    mesh_file = tmp_path / "slope.vtu"
    meshio.write(mesh_file, meshio.Mesh(np.c_[pts, np.zeros(len(pts))], cells))
    poly = soil_positions(_scene(tmp_path, f"[[particles.polygons]]\nvertices = {SLOPE}"))
    mesh = soil_positions(_scene(tmp_path, f"[[particles.meshes]]\nfile = '{mesh_file}'"))
    key = lambda a: set(map(tuple, np.round(a / 0.025).astype(int)))  # noqa: E731
    assert key(poly) == key(mesh)


@pytest.mark.parametrize("geometry, words", [
    ("[[particles.meshes]]\nfile = 'nope.msh'", ["particles.meshes[0].file", "no such file"]),
    ("[[particles.polygons]]\nvertices = [[0.0, 0.0], [5.0, 0.0], [0.0, 1.0]]",
     ["particles.polygons[0].vertices[1]", "outside the domain"]),
    ("", ["particles", "at least one"]),
])
def test_bad_geometry_is_exit_2(tmp_path, geometry, words):
    _scene_text = (tmp_path / "s.toml")
    try:
        _scene(tmp_path, geometry)
    except Exception:
        pass
    r = subprocess.run([sys.executable, "-m", "psph", "validate", str(_scene_text)],
                       capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    for w in words:
        assert w in r.stderr


def test_unreadable_mesh_is_exit_2(tmp_path):
    bad = tmp_path / "bad.vtu"
    bad.write_text("this is not a mesh")
    f = tmp_path / "s.toml"
    _scene(tmp_path, "[[particles.blocks]]\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]")
    f.write_text(f.read_text().replace(
        "[[particles.blocks]]", f"[[particles.meshes]]\nfile = '{bad}'\n[[particles.blocks]]"))
    r = subprocess.run([sys.executable, "-m", "psph", "run", str(f), "--out",
                        str(tmp_path / "o")], capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert "meshio cannot read it" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()

"""Issue 37's bad input: a symmetry plane that cuts no particle, and a scene whose particle
count would not fit in memory: exit 2, one line naming the key, nothing written."""

import os
import subprocess
import sys

import numpy as np
import pytest

from psph.config.load import load_scene
from psph.config.rules import check_symmetry_planes
from psph.errors import SceneError, SceneRule
from psph.geometry.lattice import estimate_count, extent, seed
from tests.helpers import assert_bad_input
from tests.test_bad_input import run_cli

COLUMN_3D = """
name = "block_3d"
gravity = [0.0, 0.0, 0.0]
[domain]
min = [0.0, 0.0, 0.0]
max = [0.4, 0.04, 0.2]
[material]
E = 20.0e6
nu = 0.3
porosity = 0.4
rho_s = 2650.0
k = 1.0e-4
[particles]
dx = 0.01
blocks = [{ min = [0.1, 0.0, 0.0], max = [0.3, 0.04, 0.2] }]
[pressure]
scheme = "none"
[time]
end = 1.0e-4
[boundaries]
left = { motion = "slip", symmetry = true }
front = { motion = "slip", symmetry = true }
bottom = { motion = "fixed" }
"""

# a quarter disc of soil (a polygon) against the left side, away from the right one
QUARTER_2D = """
name = "quarter_2d"
gravity = [0.0, -9.81]
[domain]
min = [0.0, 0.0]
max = [1.0, 0.5]
[material]
E = 20.0e6
nu = 0.3
porosity = 0.4
rho_s = 2650.0
k = 1.0e-4
[particles]
dx = 0.02
polygons = [{ vertices = [[0.0, 0.0], [0.4, 0.0], [0.28, 0.28], [0.0, 0.4]] }]
[pressure]
scheme = "none"
[time]
end = 1.0e-4
[boundaries]
left = { motion = "slip", symmetry = true }
right = { motion = "slip", symmetry = true }
bottom = { motion = "fixed" }
"""

# an octant of a ball of soil (radius 1 m) and a block at dx = 0.2 mm: 8.11e10 particles
BALL_3D = """
name = "fine_ball"
gravity = [0.0, 0.0, 0.0]
[domain]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[material]
E = 20.0e6
nu = 0.3
porosity = 0.4
rho_s = 2650.0
k = 1.0e-4
[particles]
dx = 2.0e-4
[[particles.spheres]]
centre = [0.0, 0.0, 0.0]
radius = 1.0
[[particles.blocks]]
min = [0.5, 0.5, 0.5]
max = [1.0, 1.0, 1.0]
[pressure]
scheme = "none"
[time]
end = 1.0e-4
[boundaries]
left = { motion = "slip", symmetry = true }
front = { motion = "slip", symmetry = true }
bottom = { motion = "slip", symmetry = true }
"""


def _scene_file(tmp_path, text, name="scene.toml"):
    f = tmp_path / name
    f.write_text(text)
    return f


def _mpi_env():
    return dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
                OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")


# ------------------------------------------------------------------ symmetry planes

@pytest.mark.parametrize("command", ["validate", "run"])
def test_a_symmetry_plane_that_is_not_a_slip_wall_is_exit_2(tmp_path, command):
    f = _scene_file(tmp_path, COLUMN_3D)
    out = tmp_path / "out"
    args = ["--out", str(out)] if command == "run" else []
    r = run_cli(command, str(f), *args, "--set",
                'boundaries.left={motion="fixed", symmetry=true}')
    assert_bad_input(r, ["boundaries.left.symmetry", "a symmetry plane is a free-slip wall",
                         'motion = "slip"', 'got motion = "fixed"'], out)


def test_a_symmetry_plane_that_touches_no_particle_is_exit_2_in_3d(tmp_path):
    """The block starts 0.1 m from the left side: its first particles are at x = 0.105 m,
    10.5 dx from the plane x = 0; the front side (y = 0) is touched."""
    f = _scene_file(tmp_path, COLUMN_3D)
    out = tmp_path / "out"
    r = run_cli("run", str(f), "--out", str(out))
    assert_bad_input(r, ["boundaries.left.symmetry", "the plane x = 0 touches no particle",
                         "nearest at x = 0.105 m", "10.5 dx", "dx = 0.01 m"], out)


def test_a_symmetry_plane_that_touches_no_particle_is_exit_2_in_2d(tmp_path):
    """A polygon against the left side (touched) and 0.6 m short of the right one."""
    f = _scene_file(tmp_path, QUARTER_2D)
    out = tmp_path / "out"
    r = run_cli("run", str(f), "--out", str(out))
    assert_bad_input(r, ["boundaries.right.symmetry", "the plane x = 1 touches no particle",
                         "nearest at x = 0.39 m", "dx = 0.02 m"], out)


def test_an_untouched_symmetry_plane_leaves_an_existing_output_alone(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("keep")
    r = run_cli("run", str(_scene_file(tmp_path, COLUMN_3D)), "--out", str(out))
    assert r.returncode == 2, r.stderr
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]
    assert (out / "summary.json").read_text() == "keep"


@pytest.mark.parametrize("name,sides", [("cryer", ["left", "front", "bottom"]),
                                        ("collapse_3d", ["left", "front"]),
                                        ("strip_footing", ["left"])])
def test_builtin_symmetry_planes_touch_their_soil(name, sides):
    scene = load_scene(name)
    marked = [s for s in ("left", "right", "front", "back", "bottom", "top")
              if getattr(scene.boundaries, s).symmetry]
    assert marked == sides
    bounds = extent(seed(scene)[0])
    check_symmetry_planes(scene, bounds)  # no SceneRule
    # moved one dx and a half off the plane, the soil no longer touches it
    for side in sides:
        shifted = bounds.copy()
        axis = "xyz".index({"left": "x", "front": "y", "bottom": "z" if scene.dim == 3
                            else "y"}[side])
        shifted[0, axis] += 1.5 * scene.particles.dx
        with pytest.raises(SceneRule) as e:
            check_symmetry_planes(scene, shifted)
        assert e.value.key == f"boundaries.{side}.symmetry"


def test_a_checkpoint_without_the_key_restarts_a_scene_with_it():
    """The key is a check, not physics: a restart may add or drop it."""
    from psph.app.restart_rules import physics_difference
    from psph.config.load import to_toml

    marked = load_scene("strip_footing")
    plain = load_scene("strip_footing", ["boundaries.left.symmetry=false"])
    assert physics_difference(to_toml(plain), marked, "ck") is None
    moved = load_scene("strip_footing", ["boundaries.left.symmetry=false",
                                         'boundaries.left.flow="drained"'])
    assert physics_difference(to_toml(moved), marked, "ck")[0] == "boundaries.left.flow"


def test_symmetry_plane_one_dx_rule():
    """Within dx of the plane passes (a lattice against the side sits at dx/2), beyond
    it does not."""
    scene = load_scene("collapse_3d")
    dx = scene.particles.dx
    bounds = np.array([[0.5 * dx, 0.5 * dx, 0.5 * dx], [1.0, 1.0, 0.5]])
    check_symmetry_planes(scene, bounds)
    bounds[0, 0] = dx
    check_symmetry_planes(scene, bounds)
    bounds[0, 0] = 1.01 * dx
    with pytest.raises(SceneRule, match="the plane x = 0 touches no particle"):
        check_symmetry_planes(scene, bounds)


# ------------------------------------------------------------------ memory

def test_estimated_particle_count_of_the_builtin_scenes():
    """Blocks exactly, a polygon's area to within a particle, the octant of a sphere and
    the quarter of a cylinder to within 1 %, a layer's bounding box above its count."""
    for name, rel in (("terzaghi_3d", 0.0), ("retrogressive_k0_0.5", 1e-4),
                      ("cryer", 0.01), ("collapse_3d", 0.01)):
        scene = load_scene(name)
        n = len(seed(scene)[0])
        assert abs(estimate_count(scene) - n) <= rel * n, name
    slope = load_scene("slope_section")
    assert estimate_count(slope) >= len(seed(slope)[0])


def test_a_scene_too_large_for_memory_is_exit_2_before_anything_is_allocated(tmp_path):
    """About 8.11e10 particles (an octant of a ball and a block) on one rank: exit 2 naming
    particles.dx, the count, the GiB needed and available, with no lattice built (a
    sphere's lattice mask alone would be 125 GB): the process's peak memory stays that of
    the interpreter and its imports."""
    f = _scene_file(tmp_path, BALL_3D)
    out = tmp_path / "out"
    code = ("import resource, sys\n"
            "from psph.app.cli import main\n"
            "rc = main(sys.argv[1:])\n"
            "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)\n"
            "sys.exit(rc)\n")
    r = subprocess.run([sys.executable, "-c", code, "run", str(f), "--out", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert_bad_input(r, ["particles.dx = 0.0002", "about 8.11e+10 particles", "estimate",
                         "1000 B each", "dry", "GiB a rank on 1 rank(s)", "GiB the node has "
                         "available (MemAvailable)"], out)
    assert int(r.stdout.split()[-1]) * 1024 < 1024 ** 3  # ru_maxrss in KiB


def test_memory_check_shares_the_particles_among_the_ranks_of_a_node():
    from mpi4py import MPI

    from psph.app.memory import STATE_BYTES_PER_PARTICLE, check_memory

    scene = load_scene("terzaghi_3d")  # 1,600 particles
    need = 1600 * STATE_BYTES_PER_PARTICLE[3, True]
    check_memory(scene, MPI.COMM_SELF, available=need * 1.01)
    with pytest.raises(SceneError, match=r"particles.dx = 0.01: about 1.6e\+03 particles"):
        check_memory(scene, MPI.COMM_SELF, available=need * 0.99)


@pytest.mark.parametrize("case", ["symmetry", "memory"])
def test_two_ranks_stop_together_with_one_line(tmp_path, case):
    """Under mpirun every rank reaches the verdict (an allreduce of the particles'
    extent, an allgather of the nodes' memory): exit 2 and rank 0's one line, no hang.
    (mpirun adds its own banner after a non-zero exit: psph's lines are those of psph.)"""
    text = COLUMN_3D if case == "symmetry" else BALL_3D
    f = _scene_file(tmp_path, text)
    out = tmp_path / "out"
    r = subprocess.run(["mpirun", "-n", "2", sys.executable, "-m", "psph", "run", str(f),
                        "--out", str(out), "--quiet"], env=_mpi_env(), capture_output=True,
                       text=True, timeout=300)
    words = ["boundaries.left.symmetry", "touches no particle"] if case == "symmetry" \
        else ["particles.dx = 0.0002", "GiB a rank on 2 rank(s)", "for the 2 on one node"]
    assert r.returncode == 2, r.stderr
    ours = [line for line in r.stderr.splitlines() if line.startswith("psph")]
    assert len(ours) == 1 and ours[0].startswith("psph: error: "), r.stderr
    assert all(w in ours[0] for w in words), (words, ours[0])
    assert "Traceback" not in r.stderr and r.stdout == ""
    assert not out.exists()

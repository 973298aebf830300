"""Rigid surfaces lined with boundary particles in 3D (issue 37): the particles of a
triangle surface (`geometry/surfaces.py`), their state (`kernels/boundary_3d.py`), the
scene keys' bad input, and a soil at rest on a surface floor."""

import itertools

import numpy as np
import pytest

from psph.geometry.surfaces import surface_particles
from psph.kernels.boundary import MOTION_FIXED, MOTION_FRICTION, MOTION_SLIP
from psph.kernels.boundary_3d import boundary_state_3d
from psph.kernels.bundles import BoundaryPoints, BoundaryRows, CellList, WallFields
from psph.kernels.neighbours import cell_lists_indexed
from psph.kernels.spline import dw_cubic, w_cubic
from tests.helpers import assert_bad_input
from tests.test_bad_input import run_cli

DX = 0.1
H = 1.3 * DX
FLOOR = (np.array([[-1.0, -1.0, 0.0], [2.0, -1.0, 0.0], [2.0, 2.0, 0.0], [-1.0, 2.0, 0.0]]),
         np.array([[0, 1, 2], [0, 2, 3]]))


def _cube(lo=0.2, hi=1.2):
    v = np.array(list(itertools.product((lo, hi), repeat=3)), float)[:, ::-1]
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2],
             [1, 3, 7, 5]]
    tri = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    return v, np.array(tri)


def test_a_floor_gets_the_lattice_rows_within_2h_below_it_with_the_upward_normal():
    x, n, foot = surface_particles(*FLOOR, "above", DX, H, [0.0, 0.0, 0.0],
                                   [-0.3, -0.3, -1.0], [1.3, 1.3, 1.0])
    assert np.allclose(np.unique(x[:, 2]), [-0.25, -0.15, -0.05])  # (k + 1/2) dx < 2h
    assert len(x) == 3 * 16 * 16  # x, y: the lattice within [lo, hi]
    assert np.array_equal(n, np.tile([0.0, 0.0, 1.0], (len(x), 1)))
    assert np.allclose(foot[:, :2], x[:, :2], rtol=0, atol=1e-14)
    assert np.allclose(foot[:, 2], 0.0, rtol=0, atol=1e-14)
    below = surface_particles(*FLOOR, "below", DX, H, [0.0, 0.0, 0.0], [0.0, 0.0, -1.0],
                              [1.0, 1.0, 1.0])
    assert np.allclose(np.unique(below[0][:, 2]), [0.05, 0.15, 0.25])
    assert np.all(below[1][:, 2] == -1.0)


@pytest.mark.parametrize("soil", ["outside", "inside"])
def test_a_closed_cube_is_lined_on_the_side_away_from_the_soil(soil):
    """Against brute force: the lattice points within 2h of the cube's surface on the
    non-soil side, with their distances; normals point to the soil."""
    v, tri = _cube()
    x, n, foot = surface_particles(v, tri, soil, DX, H, [0.0, 0.0, 0.0], [-1.0] * 3,
                                   [3.0] * 3)
    g = (np.arange(-10, 30) + 0.5) * DX
    p = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T
    lo, hi = 0.2, 1.2
    inside = np.all((p > lo) & (p < hi), axis=1)
    d_in = np.minimum(p - lo, hi - p).min(axis=1)
    d_out = np.linalg.norm(np.maximum(np.maximum(lo - p, p - hi), 0.0), axis=1)
    want = (inside & (d_in < 2 * H)) if soil == "outside" else (~inside & (d_out < 2 * H))
    assert len(x) == want.sum()
    got = {tuple(np.round(q / DX - 0.5).astype(int)) for q in x}
    assert got == {tuple(np.round(q / DX - 0.5).astype(int)) for q in p[want]}
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    toward = np.einsum("ij,ij->i", foot - x, n)  # the foot lies on the soil side
    assert np.all(toward > 0.0)
    if soil == "inside":  # beyond a corner the normal is radial, toward the corner
        corner = np.all(x > hi, axis=1)
        assert corner.any()
        radial = (hi - x[corner]) / np.linalg.norm(hi - x[corner], axis=1)[:, None]
        assert np.allclose(n[corner], radial)


def _soil_on_floor(nx=6, nz=5):
    """Soil lattice points above the floor z = 0 and its boundary particles below."""
    g = (np.arange(nx) + 0.5) * DX
    gz = (np.arange(nz) + 0.5) * DX
    soil = np.array(np.meshgrid(g, g, gz, indexing="ij")).reshape(3, -1).T
    bx, bn, _ = surface_particles(*FLOOR, "above", DX, H, [0.0, 0.0, 0.0],
                                  [-0.3, -0.3, -1.0], [nx * DX + 0.3] * 2 + [1.0])
    return soil, bx, bn


def _within_support(soil, bx):
    """Boundary particles with soil within 2h: those the Shepard averages reach."""
    d = np.linalg.norm(bx[:, None, :] - soil[None, :, :], axis=2).min(axis=1)
    return d < 2 * H


def _state(motion, soil, bx, bn, v_soil, stress_soil, tan_phi=0.0, rho=2000.0, g=9.81,
           p_soil=0.0, drained=False, p_out=None):
    ns, nb = len(soil), len(bx)
    n = ns + nb
    x = np.concatenate([soil, bx])
    cell_of, cell_start, order, ncell = cell_lists_indexed(x, H)
    v = np.zeros((n, 3))
    v[:ns] = v_soil
    stress = np.zeros((n, 6))
    stress[:ns] = stress_soil
    p = np.zeros(n)
    p[:ns] = p_soil
    z = np.zeros
    foot = np.zeros((nb, 3))  # the floor z = 0 (the cube's tests use no friction)
    pts = BoundaryPoints(np.full(nb, motion), np.full(nb, tan_phi), np.full(nb, drained),
                         bn, foot, z(nb), z(nb))
    f = WallFields(x, v, z((n, 3)), stress, p, p.copy(), np.full(n, 0.4), z(n),
                   np.full(n, rho), np.ones(n), z((n, 3)), z(n))
    boundary_state_3d(ns, BoundaryRows(ns, nb, np.arange(nb)), pts, f, z(3),
                      np.array([0.0, 0.0, -g]), CellList(cell_of, cell_start, order, ncell), H)
    if p_out is not None:
        p_out[:] = p[ns:]
    return v[ns:], stress[ns:]


def test_fixed_and_slip_surfaces_mirror_the_velocity():
    soil, bx, bn = _soil_on_floor()
    u = np.array([1.0, 0.5, -0.2])
    v_fixed, _ = _state(MOTION_FIXED, soil, bx, bn, u, 0.0)
    v_slip, _ = _state(MOTION_SLIP, soil, bx, bn, u, 0.0)
    reached = np.abs(v_fixed).sum(axis=1) > 0.0
    assert np.array_equal(reached, _within_support(soil, bx))
    assert np.allclose(v_fixed[reached], -u, rtol=0, atol=1e-14)
    assert np.allclose(v_slip[reached], [1.0, 0.5, 0.2], rtol=0, atol=1e-14)


def test_a_geostatic_stress_is_continued_linearly_below_the_floor():
    """sigma'_zz = -rho g (Z - z) in the soil: every boundary particle it reaches gets
    -rho g (Z - z_b) exactly (the weight of the soil between them, `ghosts.py`'s rule),
    its horizontal stresses the Shepard average."""
    soil, bx, bn = _soil_on_floor()
    rho, g, top = 2000.0, 9.81, 0.5
    s = np.zeros((len(soil), 6))
    s[:, 2] = -rho * g * (top - soil[:, 2])
    s[:, 0] = s[:, 1] = 0.5 * s[:, 2]
    _, sb = _state(MOTION_FIXED, soil, bx, bn, 0.0, s, rho=rho, g=g)
    reached = sb[:, 2] != 0.0
    assert np.array_equal(reached, _within_support(soil, bx))
    assert np.allclose(sb[reached, 2], -rho * g * (top - bx[reached, 2]), rtol=1e-12)
    assert np.all(sb[reached, 0] < 0.0) and not sb[:, 3:].any()


@pytest.mark.parametrize("shear, sticks", [(100.0, True), (2000.0, False)])
def test_a_friction_surface_carries_at_most_the_coulomb_traction(shear, sticks):
    """Soil under sigma'_zz = -1000 Pa with a shear traction along (1, 1, 0) on a wall
    of friction angle 30 deg, under gravity: below tan(30) x 1000 = 577 Pa it sticks
    (the shear kept), above it the pair traction (tau + tau_b) / 2 is the Coulomb limit
    along tau, of the normal stress at the surface: the soil's, continued by the weight
    of the soil between it and the surface, rho g z^ with z^ the soil's height above the
    floor averaged with the pair sum's weights |dW/dr| (z_j - z_b) / r (not the normal
    stress continued to the boundary particle's depth, more compressive)."""
    soil, bx, bn = _soil_on_floor()
    s = np.zeros((len(soil), 6))
    s[:, 2] = -1000.0
    s[:, 4] = s[:, 5] = shear / np.sqrt(2.0)  # yz, zx: tau = shear (1, 1, 0) / sqrt 2
    u = np.array([0.3, 0.3, 0.0])
    v, sb = _state(MOTION_FRICTION, soil, bx, bn, u, s, tan_phi=np.tan(np.radians(30.0)),
                   rho=2000.0)
    reached = _within_support(soil, bx)
    tau_b = sb[reached][:, [5, 4]]  # (zx, yz): the traction's x and y on the plane z
    pair = 0.5 * (tau_b + shear / np.sqrt(2.0))
    if sticks:
        assert np.allclose(tau_b, shear / np.sqrt(2.0)) and np.allclose(v[reached], -u)
    else:
        zhat = []
        for xb in bx[reached]:
            d = soil - xb
            r = np.linalg.norm(d, axis=1)
            near = (r < 2 * H) & (r > 0)
            gn = np.maximum(-np.array([dw_cubic(q, H) for q in r[near]]) * d[near, 2]
                            / r[near], 0.0)
            zhat.append((gn * soil[near, 2]).sum() / gn.sum())
        cap = np.tan(np.radians(30.0)) * (1000.0 + 2000.0 * 9.81 * np.array(zhat))
        assert np.allclose(pair, cap[:, None] / np.sqrt(2.0), rtol=1e-12)
        assert np.allclose(v[reached], u)  # slides: the tangential velocity kept
    assert np.all(sb[reached, 2] < -1000.0 - 100.0)  # the weight continued below the floor


def test_the_friction_limit_holds_for_the_pair_sum_of_a_sheared_base():
    """A shear that falls with height, as in a block sliding on the floor (the bottom
    row's far above the next): the wall's shear tau_b makes the pair sum of Eq. (26),
    sum_j g_j (tau_j + tau_b) / sum_j g_j with g_j = |dW/dr| (z_j - z_b) / r, equal to
    the Coulomb limit of each boundary particle. With the Shepard average of tau
    instead (the rule before), it would not: that average weights the upper rows more."""
    soil, bx, bn = _soil_on_floor()
    s = np.zeros((len(soil), 6))
    s[:, 2] = -1000.0
    s[:, 5] = 3000.0 * np.exp(-soil[:, 2] / DX)  # zx: the traction along x on the floor
    v, sb = _state(MOTION_FRICTION, soil, bx, bn, np.array([0.3, 0.0, 0.0]), s,
                   tan_phi=np.tan(np.radians(30.0)), rho=2000.0)
    reached = _within_support(soil, bx)
    checked = differs = 0
    for k in np.flatnonzero(reached):
        d = soil - bx[k]
        r = np.linalg.norm(d, axis=1)
        near = (r < 2 * H) & (r > 0)
        g = np.maximum(-np.array([dw_cubic(q, H) for q in r[near]]) * d[near, 2] / r[near],
                       0.0)
        if g.sum() == 0.0:
            continue
        zhat = (g * soil[near, 2]).sum() / g.sum()
        cap = np.tan(np.radians(30.0)) * (1000.0 + 2000.0 * 9.81 * zhat)
        pair = (g * (s[near, 5] + sb[k, 5])).sum() / g.sum()
        assert pair == pytest.approx(2.0 * cap, rel=1e-12)
        w = np.array([w_cubic(q, H) for q in r[near]])
        shepard = (w * s[near, 5]).sum() / w.sum()
        differs += abs(shepard - (g * s[near, 5]).sum() / g.sum()) > 10.0
        checked += 1
    assert checked > 10 and differs > 10, (checked, differs)  # the weights matter


def test_a_side_wall_continues_no_weight_and_a_drained_one_mirrors_p():
    """Around a cube (soil outside, geostatic): the boundary particles of its vertical
    faces get the soil's averaged normal stress whether gravity is on or off (the weight
    across a wall is along its normal: none on a side wall), those under its top face a
    more compressive one with gravity; drained, p_b = -p~ (p = 0 on the surface)."""
    v, tri = _cube(0.3, 0.7)
    bx, bn, _ = surface_particles(v, tri, "outside", DX, H, [0.0] * 3, [-1.0] * 3, [2.0] * 3)
    g = (np.arange(10) + 0.5) * DX
    pts = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T
    soil = pts[~np.all((pts > 0.3) & (pts < 0.7), axis=1)]
    s = np.zeros((len(soil), 6))
    s[:, 2] = -2000.0 * 9.81 * (1.0 - soil[:, 2])
    s[:, 0] = s[:, 1] = 0.5 * s[:, 2]
    _, with_g = _state(MOTION_FIXED, soil, bx, bn, 0.0, s, g=9.81)
    _, without = _state(MOTION_FIXED, soil, bx, bn, 0.0, s, g=0.0)
    p = np.zeros(len(bx))
    _state(MOTION_FIXED, soil, bx, bn, 0.0, s, p_soil=500.0, drained=True, p_out=p)
    side = np.abs(bn[:, 0]) == 1.0
    top = bn[:, 2] == 1.0
    assert side.any() and top.any()
    assert np.allclose(with_g[side, 0], without[side, 0], rtol=1e-12)
    assert np.all(with_g[top, 2] < without[top, 2] - 100.0)
    assert np.allclose(p[_within_support(soil, bx)], -500.0)


@pytest.mark.parametrize("surface, words", [
    ("{vertices=[[0,0,0],[1,0,0],[0,1,0]], triangles=[[0,1,2]], soil='outside'}",
     ["boundaries.surfaces[0]", "not closed", "soil = 'outside'"]),
    ("{vertices=[[0,0,0],[1,0,0],[0,0,1]], triangles=[[0,1,2]], soil='above'}",
     ["boundaries.surfaces[0]", "face 0 is vertical", "z(x, y)"]),
    ("{vertices=[[0,0,0],[1,0,0],[0,1,0]], triangles=[[0,1,3]], soil='above'}",
     ["boundaries.surfaces[0].triangles", "3", "from 0 to 2"]),
    ("{mesh='nowhere.stl', soil='above'}", ["boundaries.surfaces[0].mesh", "no such file"]),
    ("{soil='above'}", ["boundaries.surfaces[0]", "either mesh"]),
    ("{vertices=[[0,0,0],[1,0],[0,1,0]], triangles=[[0,1,2]], soil='above'}",
     ["boundaries.surfaces[0].vertices", "three numbers a vertex"]),
    ("{vertices=[[0,0,0],[1,0,nan],[0,1,0]], triangles=[[0,1,2]], soil='above'}",
     ["boundaries.surfaces[0].vertices", "finite"]),
    ("{vertices=[[0,0,0],[1,0,0],[0,1,0]], triangles=[[0,1,2]], soil='above', "
     "motion='friction'}", ["boundaries.surfaces[0].friction_angle", "required"]),
    ("{vertices=[[0,0,0],[1,0,0],[0,1,0]], triangles=[[0,1,2]], soil='above', "
     "weight_friction=true}", ["boundaries.surfaces[0].weight_friction", "only with motion",
                               "'fixed'"]),
])
def test_bad_surfaces_exit_2_one_line_nothing_written(tmp_path, surface, words):
    out = tmp_path / "out"
    r = run_cli("run", "collapse_3d", "--out", str(out), "--set",
                f"boundaries.surfaces=[{surface}]")
    assert_bad_input(r, words, out)


def test_surfaces_are_3d_only(tmp_path):
    r = run_cli("validate", "terzaghi", "--set", "boundaries.surfaces=[{vertices=[[0,0,0],"
                "[1,0,0],[0,1,0]], triangles=[[0,1,2]], soil='above'}]")
    assert_bad_input(r, ["boundaries.surfaces", "3D only", "polylines"])


# a floor surface under the whole domain, beyond the symmetry planes by more than 2h
FLOOR_SURFACE = ("boundaries.surfaces=[{vertices=[[-1.0,-1.0,0.0],[2.0,-1.0,0.0],"
                 "[2.0,2.0,0.0],[-1.0,2.0,0.0]], triangles=[[0,1,2],[0,2,3]], "
                 "soil='above'}]")


def test_a_block_rests_on_a_surface_floor_with_its_geostatic_stress(tmp_path):
    """A dry elastic block (0.4 m cube, dx = 0.05 m) between slip walls on a fixed floor
    given as a surface: after 0.1 s it is at rest and its bottom row carries the weight
    above it, sigma'_zz = -rho g (H - z), as on the mirror floor (to 1e-7 there)."""
    from psph.app.run import run
    from psph.config.load import load_scene
    from psph.io.snapshots import read_snapshots

    scene = load_scene("collapse_3d", [
        "domain.max=[0.4, 0.4, 0.6]", "particles.dx=0.05", "particles.cylinders=[]",
        "particles.blocks=[{min=[0.0, 0.0, 0.0], max=[0.4, 0.4, 0.4]}]",
        "boundaries.right={motion='slip'}", "boundaries.back={motion='slip'}",
        "boundaries.bottom={motion='free'}", FLOOR_SURFACE,
        "material.plasticity.c=1e6", "material.plasticity.c_r=1e6", "time.end=0.1",
        "output.interval=0.1", "verification.reference='none'"])
    run(scene, tmp_path, quiet=True)
    last = read_snapshots(tmp_path / "particles.h5")[-1]
    x, v, stress = last["x"], last["v"], last["stress"]
    assert np.abs(v).max() < 1e-5
    assert x[:, 2].min() > 0.0249
    bottom = x[:, 2] < 0.05
    geostatic = -2650.0 * 0.6 * 9.81 * (0.4 - x[bottom, 2])
    assert np.allclose(stress[bottom, 2] / geostatic, 1.0, rtol=0, atol=1e-3)

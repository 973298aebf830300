"""Mirror-ghost walls in the pair sums: a fixed (no-slip) wall resists shear but does not
feign stretching along itself (`interactions.py`, the Gs columns)."""

import numpy as np
import pytest

from psph.kernels.bundles import GhostSources, WallFields, Walls
from psph.kernels.ghosts import make_ghosts
from psph.kernels.sum_columns import GN, GS, GV, GV_XY
from tests.helpers import inverse_moment, sums_for

DX = 0.1
H = 1.3 * DX


def _block_on_wall(fixed: bool, velocity: tuple[float, float]):
    """A 12 x 6 lattice block on the wall y = 0 (soil above), moving rigidly at
    `velocity`, with its ghosts; returns the sums and the number of real particles."""
    g = (np.arange(12) + 0.5) * DX
    gy = (np.arange(6) + 0.5) * DX
    x_real = np.array(np.meshgrid(g, gy)).reshape(2, -1).T
    n = len(x_real)
    cap = 4 * n
    z = np.zeros
    x = z((cap, 2))
    x[:n] = x_real
    v = z((cap, 2))
    v[:n] = velocity
    v_slip = z((cap, 2))
    stress, p, p_prev = z((cap, 4)), z(cap), z(cap)
    poro, vol = np.full(cap, 0.4), np.full(cap, DX * DX)
    rho, perm, acc, key = np.ones(cap), np.ones(cap), z((cap, 2)), np.arange(cap, dtype=float)
    walls = Walls(np.array([1]), np.array([0.0]), np.array([1.0]), np.array([fixed]),
                  np.array([False]))
    f = WallFields(x, v, v_slip, stress, p, p_prev, poro, vol, rho, perm, acc, key)
    ng = make_ghosts(n, cap, 2.0 * H, float(cap), walls, f, np.zeros(2), np.zeros(2),
                     GhostSources(np.zeros(cap, np.int64), np.ones(cap)))
    assert ng > 0
    m = n + ng
    sums = sums_for(x[:m], H, vol[:m], v=v[:m], poro=poro[:m], n_owned=n, v_slip=v_slip[:m],
                    n_real=n)
    return sums[:n], x_real


def _gradient(g, sums):
    return g.reshape(-1, 2, 2) @ inverse_moment(sums)


@pytest.mark.parametrize("fixed", [True, False])
def test_a_block_sliding_on_a_wall_does_not_stretch(fixed):
    sums, x = _block_on_wall(fixed, (5.0, 0.0))
    # Gv + Gs: the velocity gradient with the ghosts' free-slip mirror velocity
    stretch = _gradient(sums[:, GV] + sums[:, GS], sums)
    div_v = stretch[:, 0, 0] + stretch[:, 1, 1]
    # rigid translation: no volume change anywhere, the block's front corner included
    assert np.abs(div_v).max() < 1e-9
    # Eq. (24): the porosity rate of a rigid motion is zero too
    gn = _gradient(sums[:, GN], sums)
    assert np.abs(gn[:, 0, 0] + gn[:, 1, 1]).max() < 1e-9


def test_a_fixed_wall_still_resists_sliding_by_shear():
    sums, x = _block_on_wall(True, (5.0, 0.0))
    bottom = x[:, 1] < DX
    # the plain shear rate du/dy of the bottom row sees the no-slip ghosts (-v)
    du_dy = sums[bottom, GV_XY]
    assert (du_dy > 0.5 * 5.0 / DX).all()
    # the no-slip velocity gradient itself stretches the block's corners: this is what
    # Eq. (24)-(25) took before the Gs columns (run-away suction at a debris front)
    full = _gradient(sums[:, GV], sums)
    front = bottom & (x[:, 0] > 1.1)
    assert (full[front, 0, 0] + full[front, 1, 1] > 1.0 / DX).all()


def test_free_slip_ghosts_need_no_stretching_correction():
    sums, _ = _block_on_wall(False, (5.0, -1.0))
    assert not sums[:, GS].any()
    sums, _ = _block_on_wall(True, (5.0, -1.0))
    assert sums[:, GS].any()


@pytest.mark.parametrize("drained", [False, True])
def test_ghosts_continue_a_geostatic_stress_linearly(drained):
    """Under gravity the wall-normal total stress sigma'_yy - p of a bottom wall's ghost is
    the linear continuation of the real particles' (gradient rho g, the weight of the soil
    between them), on an impermeable wall (p continued hydrostatically) and on a drained
    one (p mirrored through 0): the kink of a plain mirror excited the odd-even mode of
    sigma' (issue 16, bench/diagnostics/oddeven_stress_mode.py). sigma'_xx and sigma'_zz stay
    mirrored, the shear stress as before."""
    g, rho, rho_l = 9.81, 2000.0, 1000.0
    gx = (np.arange(4) + 0.5) * DX
    gy = (np.arange(4) + 0.5) * DX
    x_real = np.array(np.meshgrid(gx, gy)).reshape(2, -1).T
    n, cap = len(x_real), 64
    z = np.zeros
    x = z((cap, 2))
    x[:n] = x_real
    y = x_real[:, 1]
    total = -rho * g * (2.0 - y)  # sigma_yy, linear in y with slope rho g
    p = z(cap)
    p[:n] = 5000.0 * y if drained else rho_l * g * (2.0 - y)
    stress = z((cap, 4))
    stress[:n, 1] = total + p[:n]
    stress[:n, 0] = stress[:n, 2] = 0.5 * stress[:n, 1]
    stress[:n, 3] = 10.0 * y
    src, sign = np.zeros(cap, np.int64), np.ones(cap)
    walls = Walls(np.array([1]), np.array([0.0]), np.array([1.0]), np.array([True]),
                  np.array([drained]))
    f = WallFields(x, z((cap, 2)), z((cap, 2)), stress, p, p.copy(), np.full(cap, 0.4),
                   np.ones(cap), np.full(cap, rho), np.ones(cap), z((cap, 2)),
                   np.arange(cap, dtype=float))
    ng = make_ghosts(n, cap, 2.0 * H, float(cap), walls, f, np.array([0.0, -rho_l * g]),
                     np.array([0.0, -g]), GhostSources(src, sign))
    gh = np.arange(n, n + ng)
    assert ng == 12 and np.all(x[gh, 1] < 0.0)  # the rows within 2h = 2.6 dx
    yg = x[gh, 1]
    assert np.allclose(stress[gh, 1] - p[gh], -rho * g * (2.0 - yg), rtol=1e-12)
    assert np.allclose(stress[gh, 0], stress[src[gh], 0])
    assert np.allclose(stress[gh, 2], stress[src[gh], 2])
    assert np.allclose(stress[gh, 3], stress[src[gh], 3])


def test_a_lid_takes_no_weight():
    """A top wall does not carry the soil (gravity points away from it): its ghosts
    mirror the stress (no pore pressure here) without the weight, so a lid does not hold
    the soil up with a tension."""
    g, rho = 9.81, 2000.0
    gx = (np.arange(4) + 0.5) * DX
    gy = 1.0 - (np.arange(4) + 0.5) * DX  # the rows under a lid at y = 1
    x_real = np.array(np.meshgrid(gx, gy)).reshape(2, -1).T
    n, cap = len(x_real), 64
    z = np.zeros
    x = z((cap, 2))
    x[:n] = x_real
    stress = z((cap, 4))
    stress[:n, 1] = -rho * g * (1.0 - x_real[:, 1])
    stress[:n, 0] = stress[:n, 2] = 0.5 * stress[:n, 1]
    src, sign = np.zeros(cap, np.int64), np.ones(cap)
    p = z(cap)
    walls = Walls(np.array([1]), np.array([1.0]), np.array([-1.0]), np.array([True]),
                  np.array([False]))
    f = WallFields(x, z((cap, 2)), z((cap, 2)), stress, p, p.copy(), np.full(cap, 0.4),
                   np.ones(cap), np.full(cap, rho), np.ones(cap), z((cap, 2)),
                   np.arange(cap, dtype=float))
    ng = make_ghosts(n, cap, 2.0 * H, float(cap), walls, f, np.zeros(2), np.array([0.0, -g]),
                     GhostSources(src, sign))
    gh = np.arange(n, n + ng)
    assert ng > 0 and np.all(x[gh, 1] > 1.0)
    assert np.array_equal(stress[gh, :3], stress[src[gh], :3])


def test_plane_walls_are_the_sides_that_move_not_freely():
    """`plane_walls`: each side whose motion is not "free", in the order left, right,
    bottom, top, as the plane x[axis] = pos of the domain box, the sign of the soil's side
    and whether it is fixed (no-slip)."""
    from psph.config.boundaries import Boundaries, Boundary, plane_walls

    walls = plane_walls(Boundaries(right=Boundary(motion="slip"),
                                   bottom=Boundary(motion="fixed")), [1.0, -2.0], [5.0, 3.0])
    assert walls.sides == ["right", "bottom"]
    assert walls.axis.tolist() == [0, 1] and walls.pos.tolist() == [5.0, -2.0]
    assert walls.sign.tolist() == [-1.0, 1.0] and walls.fixed.tolist() == [False, True]
    assert plane_walls(Boundaries(), [0.0, 0.0], [1.0, 1.0]).sides == []

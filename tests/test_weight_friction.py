"""The Coulomb friction of a particle's own weight on a `weight_friction` wall
(`kernels/boundary.boundary_contact`; issue 37, the film of `collapse_3d` at the
Drucker-Prager apex, docs/vv/collapse_3d.md). In a run: `tests/test_three_d.py`,
`test_collapse_3d_quarter_column_spreads_and_stops`."""

import numpy as np

from psph.kernels.boundary import boundary_contact
from psph.kernels.bundles import BoundaryPoints, BoundaryRows, ContactFields, ContactGrid
from psph.kernels.neighbours import bin_particles, grid_bounds

DX = 0.05
H = 1.2 * DX
RHO = 2000.0


def _contact(x, v, weight_dv, stress=None, rho_water=0.0):
    """boundary_contact of particles x (2D or 3D) over a floor (z = 0, y = 0 in 2D) lined
    with one boundary particle dx/2 under each (normal up). Returns (x, v) after it."""
    n, dim = x.shape
    bx = x.copy()
    bx[:, -1] = -0.5 * DX
    allx = np.vstack([x, bx])
    cell = 2 * H
    origin = allx.min(axis=0) - 4 * cell
    lo = np.zeros(dim, np.int64)
    ncell = np.zeros(dim, np.int64)
    grid_bounds(allx, 2 * n, origin, cell, np.full(dim, 1 << 40, np.int64), lo, ncell)
    nc = int(ncell.prod())
    cell_start = np.zeros(nc + 1, np.int64)
    order = np.zeros(2 * n, np.int64)
    bin_particles(allx, np.arange(2 * n, dtype=float), 2 * n, origin, cell, lo, ncell,
                  np.zeros(2 * n, np.int64), cell_start, np.zeros(nc + 1, np.int64), order)
    normal = np.zeros((n, dim))
    normal[:, -1] = 1.0
    foot = bx.copy()
    foot[:, -1] = 0.0
    vv = np.vstack([v, np.zeros_like(v)])
    f = ContactFields(allx, vv, np.zeros_like(allx), _stress(stress, n, dim),
                      np.full(2 * n, RHO))
    z = np.zeros
    pts = BoundaryPoints(z(n, np.int64), z(n), z(n, np.bool_), normal, foot,
                         np.full(n, weight_dv), np.full(n, 0.5 * 9.81 * DX))
    boundary_contact(n, f, BoundaryRows(n, n, np.arange(n)), pts,
                     ContactGrid(origin, lo, ncell, cell_start, order), cell, H, DX, rho_water)
    return allx[:n], vv[:n]


def _stress(szz, n: int, dim: int) -> np.ndarray:
    """Stresses (2n rows) with sigma'_nn = szz[i] on the soil rows (zero if None)."""
    s = np.zeros((2 * n, 6 if dim == 3 else 4))
    if szz is not None:
        s[:n, dim - 1] = szz
    return s


def test_the_tangential_velocity_loses_at_most_the_weights_friction():
    """Within dx of the floor: |v_t| falls by min(|v_t|, dv) along itself, v_n is kept;
    a particle higher up keeps its velocity."""
    x = np.array([[0.0, 0.0, 0.025], [1.0, 0.0, 0.025], [2.0, 0.0, 0.049],
                  [3.0, 0.0, 0.075]])
    v = np.array([[3.0, 4.0, -0.5], [0.03, -0.04, 0.2], [0.0, 0.0, 1.0], [3.0, 4.0, 0.0]],
                 float)
    _, out = _contact(x, v, 0.1)
    assert np.allclose(out[0], [3.0 * 0.98, 4.0 * 0.98, -0.5], rtol=0, atol=1e-15)
    assert np.allclose(out[1], [0.0, 0.0, 0.2], rtol=0, atol=1e-15)  # stopped, not reversed
    assert np.array_equal(out[2], v[2])  # no tangential velocity
    assert np.array_equal(out[3], v[3])  # beyond dx
    assert np.array_equal(_contact(x, v, 0.0)[1], v)  # no weight friction: unchanged


def test_a_particle_put_back_above_the_wall_then_gets_the_friction():
    """Found 0.01 m below the floor: reflected to 0.01 m above it, its velocity into the
    wall removed, then (within dx) its tangential velocity reduced by dv."""
    x, v = _contact(np.array([[0.0, 0.0, -0.01]]), np.array([[1.0, 0.0, -0.5]]), 0.1)
    assert np.allclose(x[0], [0.0, 0.0, 0.01], rtol=0, atol=1e-15)
    assert np.allclose(v[0], [0.9, 0.0, 0.0], rtol=0, atol=1e-15)


def test_the_weight_friction_in_2d():
    """The same rule on a 2D polyline's boundary particles (the kernel serves both)."""
    x = np.array([[0.0, 0.025], [1.0, 0.025], [2.0, 0.075]])
    v = np.array([[-0.3, -0.1], [0.05, 0.0], [0.3, 0.0]])
    _, out = _contact(x, v, 0.1)
    assert np.allclose(out, [[-0.2, -0.1], [0.0, 0.0], [0.3, 0.0]], rtol=0, atol=1e-15)


def test_only_the_weight_its_own_stress_does_not_carry():
    """A particle whose sigma'_nn holds half a particle's weight, rho g dx / 2, gets no
    weight friction (the wall's stress-based Coulomb limit counts its weight:
    `boundary_3d`); at a quarter of it, half the friction; in tension, all of it (the
    Drucker-Prager apex's film)."""
    half = RHO * 9.81 * 0.5 * DX
    x = np.array([[0.0, 0.0, 0.025], [1.0, 0.0, 0.025], [2.0, 0.0, 0.025],
                  [3.0, 0.0, 0.025]])
    v = np.tile([1.0, 0.0, 0.0], (4, 1))
    _, out = _contact(x, v, 0.1, stress=[-half, -2.0 * half, -0.5 * half, 100.0])
    assert np.allclose(out[:, 0], [1.0, 1.0, 0.95, 0.9], rtol=0, atol=1e-12)


def test_the_share_in_2d():
    """The same share on a 2D polyline's floor (sigma'_yy the normal stress)."""
    half = RHO * 9.81 * 0.5 * DX
    x = np.array([[0.0, 0.025], [1.0, 0.025], [2.0, 0.025]])
    v = np.tile([1.0, 0.0], (3, 1))
    _, out = _contact(x, v, 0.1, stress=[-half, -0.5 * half, 0.0])
    assert np.allclose(out[:, 0], [1.0, 0.95, 0.9], rtol=0, atol=1e-12)



def test_a_saturated_particle_counts_its_buoyant_weight():
    """With pore water (rho_water = rho_l) the share compares sigma'_nn with the buoyant
    weight (rho - rho_l) g dx / 2, and the friction acts on it: dv (rho - rho_l) / rho."""
    def vx(szz, rho_water):
        x = np.array([[0.0, 0.0, 0.025]])
        v = np.array([[1.0, 0.0, 0.0]])
        return _contact(x, v, 0.1, stress=szz, rho_water=rho_water)[1][0, 0]

    buoyant = (RHO - 1000.0) / RHO
    # at the apex: all of the buoyant weight's friction
    assert vx(0.0, 1000.0) == 1.0 - 0.1 * buoyant
    # sigma'_nn holding a quarter of the buoyant half weight: three quarters of it
    quarter = -0.25 * (RHO - 1000.0) * 0.5 * 9.81 * DX
    assert np.isclose(vx(quarter, 1000.0), 1.0 - 0.75 * 0.1 * buoyant, rtol=0, atol=1e-15)
    # the same stress holds only an eighth of the dry particle's half weight
    assert np.isclose(vx(quarter, 0.0), 1.0 - 0.875 * 0.1, rtol=0, atol=1e-15)
    # the buoyant half weight carried (a little more, clear of round-off): no friction
    # (the dry rule would still add some)
    held = -1.01 * (RHO - 1000.0) * 0.5 * 9.81 * DX
    assert vx(held, 1000.0) == 1.0
    assert vx(held, 0.0) < 1.0


def test_the_wall_takes_the_pore_water_density_only_in_a_saturated_scene():
    """`BoundaryParticles.rho_water`: rho_l when the scene solves a pore pressure, 0 when
    dry (the buoyant weight of `boundary_contact`)."""
    from psph.config.load import load_scene
    from psph.solver.boundary import BoundaryParticles

    dry = load_scene("collapse_3d", ["particles.dx=0.1"])
    wet = load_scene("collapse_3d", ["particles.dx=0.1", "pressure.scheme='tpi'",
                                     "material.rho_l=1020.0"])
    assert BoundaryParticles(dry, 1e9).rho_water == 0.0
    assert BoundaryParticles(wet, 1e9).rho_water == 1020.0

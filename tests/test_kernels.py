"""Kernel property tests: Eq. (21)-(23) and the fused pair loop."""

import math

import numpy as np
import pytest
from helpers import inverse_moment, jittered_lattice, sums_for

from psph.kernels.spline import dw_cubic, w_cubic
from psph.kernels.sum_columns import DVDT, GP, GV, M_XX, M_XY, SUM_A, SUM_AP, Q


def test_kernel_normalised_and_smooth():
    h = 0.7
    r = np.linspace(0, 2 * h, 4001)
    w = np.array([w_cubic(ri, h) for ri in r])
    integral = np.trapezoid(2 * math.pi * r * w, r)
    assert integral == pytest.approx(1.0, rel=1e-6)
    # derivative matches a finite difference, kernel continuous at q = 1 and vanishes at 2h
    for ri in (0.3 * h, 0.999 * h, 1.001 * h, 1.7 * h):
        fd = (w_cubic(ri + 1e-7, h) - w_cubic(ri - 1e-7, h)) / 2e-7
        assert dw_cubic(ri, h) == pytest.approx(fd, rel=1e-5)
    assert w_cubic(h * (1 - 1e-12), h) == pytest.approx(w_cubic(h * (1 + 1e-12), h))
    assert w_cubic(2 * h, h) == 0.0 and dw_cubic(2 * h, h) == 0.0


def test_partition_of_unity_on_lattice():
    dx, h = 0.1, 0.12
    x = jittered_lattice(20, dx, 0.0)
    vol = np.full(len(x), dx * dx)
    inner = np.all((x > 4 * h) & (x < 20 * dx - 4 * h), axis=1)
    d = x[inner][:, None, :] - x[None, :, :]
    r = np.linalg.norm(d, axis=2)
    total = np.vectorize(w_cubic)(r, h) @ vol
    assert np.allclose(total, 1.0, atol=5e-3)


@pytest.mark.parametrize("jitter", [0.0, 0.2])
def test_corrected_gradient_exact_for_linear_fields(jitter):
    """Eq. (22): the corrected gradient of a linear field is exact, even near the edges."""
    dx, h = 0.1, 0.13
    x = jittered_lattice(16, dx, jitter)
    n = len(x)
    vol = np.full(n, dx * dx)
    v = np.column_stack([0.3 * x[:, 0] - 1.2 * x[:, 1], 2.0 * x[:, 0] + 0.5 * x[:, 1]])
    p = 4.0 * x[:, 0] - 7.0 * x[:, 1] + 1.0
    s = sums_for(x, h, vol, v=v, p=p)
    minv = inverse_moment(s)
    grad_p = np.einsum("in,inm->im", s[:, GP], minv)
    grad_v = np.einsum("ian,inb->iab", s[:, GV].reshape(-1, 2, 2), minv)
    assert np.allclose(grad_p, [4.0, -7.0], atol=1e-9)
    assert np.allclose(grad_v, [[0.3, -1.2], [2.0, 0.5]], atol=1e-9)


def test_second_derivative_of_quadratic_eq23():
    """Eq. (23) with its correction term: Laplacian of x^2 + 3 y^2 is 8 in the interior of a
    disordered particle set, and the Laplacian of a linear field vanishes everywhere."""
    dx, h = 0.05, 0.065
    x = jittered_lattice(30, dx, 0.15)
    n = len(x)
    vol = np.full(n, dx * dx)
    for field, expected in ((x[:, 0] ** 2 + 3 * x[:, 1] ** 2, 8.0),
                            (2 * x[:, 0] - x[:, 1], 0.0)):
        s = sums_for(x, h, vol, p=field)
        minv = inverse_moment(s)
        grad = np.einsum("in,inm->im", s[:, GP], minv)
        lap = s[:, SUM_AP] - field * s[:, SUM_A] - np.sum(grad * s[:, Q], axis=1)
        inner = np.all((x > 3 * h) & (x < 30 * dx - 3 * h), axis=1)
        if expected == 0.0:
            assert np.allclose(lap, 0.0, atol=1e-8)
        else:
            assert np.mean(lap[inner]) == pytest.approx(expected, rel=0.01)
            assert np.max(np.abs(lap[inner] - expected)) < 0.15 * expected


def test_pair_loop_matches_brute_force():
    """The half-stencil cell loop visits every pair once: compare with an all-pairs sum."""
    dx, h = 0.1, 0.12
    x = jittered_lattice(12, dx, 0.3, seed=3)
    n = len(x)
    rng = np.random.default_rng(0)
    vol = rng.uniform(0.8, 1.2, n) * dx * dx
    v = rng.normal(size=(n, 2))
    stress = rng.normal(size=(n, 4))
    p = rng.normal(size=n)
    rho = rng.uniform(1.5, 2.0, n)
    s = sums_for(x, h, vol, v=v, p=p, stress=stress, rho=rho)
    ref = np.zeros((n, 4))
    for i in range(n):
        for j in range(n):
            d = x[j] - x[i]
            r = np.hypot(*d)
            if i == j or r >= 2 * h:
                continue
            g = -dw_cubic(r, h) * d / r
            ref[i, 0:2] += vol[j] * np.outer(d, g)[0]
            sig = np.array([[stress[i, 0] + stress[j, 0] - p[i] - p[j],
                             stress[i, 3] + stress[j, 3]],
                            [stress[i, 3] + stress[j, 3],
                             stress[i, 1] + stress[j, 1] - p[i] - p[j]]])
            ref[i, 2:4] += vol[j] * sig @ g / rho[i]
    assert np.allclose(s[:, M_XX:M_XY + 1], ref[:, 0:2], rtol=1e-12, atol=1e-12)
    assert np.allclose(s[:, DVDT], ref[:, 2:4], rtol=1e-10, atol=1e-10)


def test_wall_ghost_pairs_carry_no_artificial_viscosity_in_a_dry_scene():
    """Issue 37, thin layers: a particle approaching a wall at v_n approaches its mirror
    ghost at 2 v_n, and the Monaghan viscosity of that pair was a wall-normal dashpot
    that carried a one-row layer's weight (docs/vv/collapse_3d.md, cause 1). In a dry
    sweep (coupled False) a ghost pair has none; between real particles, and on ghost
    pairs of a coupled sweep, it stays."""
    from psph.kernels.bundles import PairFields, PairParams, PairRecord, sorted_cells
    from psph.kernels.interactions import pair_sums
    from psph.kernels.neighbours import cell_lists
    from psph.kernels.sum_columns import DVDT, NSUMS

    dx, h = 0.1, 0.12
    # a real particle falling toward the floor y = 0, its mirror ghost (row 2), and a
    # second real particle above approaching it
    x = np.array([[0.0, 0.5 * dx], [0.0, 1.5 * dx], [0.0, -0.5 * dx]])
    v = np.array([[0.0, -1.0], [0.0, -3.0], [0.0, 1.0]])
    n = len(x)
    z = np.zeros
    fields = PairFields(x, v, v.copy(), z((n, 4)), z(n), z(n), np.full(n, 0.4),
                        np.full(n, dx * dx), np.full(n, 2000.0), np.ones(n), z((n, 2)),
                        z((n, 3)))
    cells = sorted_cells(*cell_lists(x, h), x)
    rec = PairRecord(z((0, 2), np.int64), z((0, 2)))

    def acc(coupled, av_alpha):
        sums = z((n, NSUMS))
        par = PairParams(h, av_alpha=av_alpha, c_sound=20.0, coupled=coupled).typed()
        pair_sums(n, 2, 2, fields, cells, par, sums, rec)
        return sums[:2, DVDT.start + 1]

    plain = acc(False, 0.0)
    dry, wet = acc(False, 1.0), acc(True, 1.0)
    real_pair = acc(False, 1.0) - plain  # particle 0's viscosity with particle 1 only...
    assert abs(real_pair[1]) > 0.0  # ...and particle 1's with 0: real pairs keep it
    # particle 0 feels particle 1's viscosity in both; the ghost's only in the coupled one
    ghost_dry = dry[0] - plain[0] - (dry[1] - plain[1]) * (-1.0)
    ghost_wet = wet[0] - plain[0] - (dry[1] - plain[1]) * (-1.0)
    assert abs(ghost_dry) < 1e-12 * abs(real_pair[1])
    assert ghost_wet > 0.1 * abs(real_pair[1])  # the coupled sweep's dashpot pushes it up

"""The pore pressure in the momentum Eq. (26): pair-symmetric sum or corrected gradient
(`pressure.momentum`, issue 13 cause 12)."""

import numpy as np
from helpers import jittered_lattice, sums_for

from psph.kernels.sum_columns import DVDT
from psph.kernels.update import pore_pressure_force


def _pressure_acceleration(x, p, rho, p_weight, dx, h):
    n = len(x)
    sums = sums_for(x, h, np.full(n, dx * dx), p=p, rho=rho, p_weight=p_weight)
    if p_weight == 0.0:
        pore_pressure_force(n, sums, rho, True, 1.0, 1.0)
    return sums[:, DVDT]


def test_gradient_form_is_exact_for_a_hydrostatic_field_on_a_disordered_lattice():
    """A linear p (hydrostatic: p = p0 + gamma (H - y)) on a jittered lattice: the corrected
    gradient gives dv/dt = -grad p / rho at every interior particle to round-off, where the
    pair-symmetric sum carries -2 p_i S_i / rho_i, which grows with p_i (cause 12: a basal
    particle under 100 kPa held its place with 2.6x its neighbours' pressure). Measured on
    this lattice (jitter 0.15 dx, p about 200 kPa): the pair form's worst interior error
    is 55 |grad p / rho|, the gradient form's 9e-15."""
    dx, h = 0.1, 0.12
    x = jittered_lattice(16, dx, 0.15)
    gamma, p0 = 1.0e4, 2.0e5
    p = p0 + gamma * (1.6 - x[:, 1])
    rho = np.full(len(x), 2000.0)
    exact = np.array([0.0, gamma / 2000.0])
    inner = np.all((x > 4 * h) & (x < 1.6 - 4 * h), axis=1)
    grad = _pressure_acceleration(x, p, rho, 0.0, dx, h)[inner]
    pair = _pressure_acceleration(x, p, rho, 1.0, dx, h)[inner]
    assert np.max(np.abs(grad - exact)) < 1e-9 * exact[1]
    assert np.max(np.abs(pair - exact)) > 10.0 * exact[1]


def test_gradient_form_leaves_the_effective_stress_in_the_pair_sum():
    """p_weight = 0 removes only the pore pressure: a uniform sigma' still sums to its
    divergence (0 inside), and the sweep with p = 0 is the same either way."""
    dx, h = 0.1, 0.12
    x = jittered_lattice(12, dx, 0.1)
    n = len(x)
    stress = np.tile([-3e4, -5e4, -2e4, 1e3], (n, 1))
    rho = np.full(n, 1800.0)
    vol = np.full(n, dx * dx)
    a = sums_for(x, h, vol, stress=stress, rho=rho, p_weight=1.0)
    b = sums_for(x, h, vol, stress=stress, rho=rho, p_weight=0.0)
    assert np.array_equal(a, b)

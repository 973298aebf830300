"""The Section 4.2 and 4.3 references themselves: limits with known answers."""

import math

import numpy as np
import pytest

from psph.verify.harmonic import HarmonicColumn
from psph.verify.strip import undrained_pressure

COLUMN = dict(height=10.0, modulus=3.33e7, density=1670.0, porosity=0.33, bulk_water=1e9,
              gamma_l=9810.0, load=3e3, omega=75.0, damping=50.0)


def test_strip_load_under_the_centre_and_far_away():
    # directly under the centre at depth b the strip subtends 90 degrees: p = q / 2
    assert undrained_pressure(1e4, 0.6, 0.0, 0.6) == pytest.approx(5e3, rel=1e-12)
    # at the surface under the load alpha -> pi (p -> q); far away p -> 0
    assert undrained_pressure(1e4, 0.6, 0.0, 1e-9) == pytest.approx(1e4, rel=1e-6)
    assert undrained_pressure(1e4, 0.6, 50.0, 1.0) < 1e-3 * 1e4


def test_harmonic_reference_undrained_and_drained_limits():
    """Slow load (quasi-static). Nearly impervious soil: below the thin drained layer p
    follows the undrained share (K_l/n) / (K_l/n + M) of the load. Very permeable soil:
    p is the quasi-steady parabola S q'(t) (2 L z - z^2) / (2 c_v), S = (1/M) / (n/K_l +
    1/M), c_v = (k / gamma_l) / (n/K_l + 1/M), of a drained top and an impervious base."""
    col = HarmonicColumn(conductivity=1e-9, **(COLUMN | {"omega": 5.0}))
    t, p = col.pressure_at([5.0], math.pi / 5.0, 1e-2, nz=500)
    kn = 1e9 / 0.33
    share = kn / (kn + 3.33e7)
    q = 3e3 * (1 - np.cos(5.0 * t))
    assert np.max(np.abs(p[:, 0] - share * q)) < 0.02 * 6e3
    # undamped and slow (omega far below the column's first mode, ~22 rad/s): the global
    # damping would make the skeleton lag by c_d rho L^2 / M ~ 0.25 s
    fast = HarmonicColumn(conductivity=1.0, **(COLUMN | {"omega": 1.0, "damping": 0.0}))
    z = np.array([0.5, 5.0, 9.9])
    t, pd = fast.pressure_at(z, math.pi, 1e-2, nz=500)
    storage = 0.33 / 1e9 + 1 / 3.33e7
    cv = (1.0 / 9810.0) / storage
    rate = 3e3 * 1.0 * np.sin(1.0 * t)
    parabola = (1 / 3.33e7) / storage * rate[:, None] * (2 * 10.0 * z - z * z) / (2 * cv)
    assert parabola.max() > 40.0  # a real, non-zero profile
    # the parabola drops p's own storage rate, a relative correction of order
    # omega L^2 / c_v = 0.03, and the start-up wave adds ~1 Pa; the grid solution must sit
    # within twice that
    assert np.max(np.abs(pd - parabola)) < 0.06 * parabola.max()


def test_harmonic_reference_converges_with_the_grid():
    col = HarmonicColumn(conductivity=1e-2, **COLUMN)
    depths = [0.4, 1.0, 2.0, 5.0]
    _, coarse = col.pressure_at(depths, 0.1, 1e-3, nz=500)
    _, fine = col.pressure_at(depths, 0.1, 1e-3, nz=1000)
    assert np.max(np.abs(coarse - fine)) < 0.005 * 6e3

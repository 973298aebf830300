"""The flow rule's porosity bound (psph/verify/porosity.py) against the return mapping."""

import math

import numpy as np
import pytest

from psph.kernels.bundles import DruckerPrager
from psph.kernels.plasticity import dp_return
from psph.verify.porosity import porosity_bound, porosity_deficit


def test_constant_dilatancy_closed_form():
    """s_f = 0: n_law = 1 - (1 - n0) exp(-3 sqrt(3) xi_psi eps_p), xi of Eq. (16)."""
    t = math.tan(math.radians(-5.0))
    xi = t / math.sqrt(9 + 12 * t * t)
    eps = np.array([0.0, 0.1, 1.0, 3.0])
    want = 1 - 0.6 * np.exp(-3 * math.sqrt(3) * xi * eps)
    assert np.allclose(porosity_bound(eps, 0.4, -5.0, 0.0), want, rtol=1e-12, atol=0)


def test_the_bound_is_the_compaction_the_return_mapping_makes():
    """Drained simple shear of a Section 4.5 clay point (psi0 = -5 deg, s_f = 0.5) at a
    constant mean effective stress (an elastic volume change restores it): the plastic
    volumetric strain that `dp_return` puts in, read from the trace of its stress
    correction (3K tr d eps_p), integrates through Eq. (8) to the bound at the accumulated
    eps_p (measured: n 0.262207 against 0.262212 at eps_p 2.31), within 0.2 % of the
    compaction."""
    E, nu = 12.5e6, 0.33
    shear = E / (2 * (1 + nu))
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    bulk = lam + 2 * shear / 3
    dp = DruckerPrager(math.radians(10.0), math.radians(5.0), 55e3, 0.7e3, math.radians(-5.0),
                       5.0, 0.5)
    s = np.array([-100e3, -100e3, -100e3, 0.0])
    eps_p = ev_p = 0.0
    d_gamma = 2e-4  # engineering shear strain per step
    for _ in range(20000):
        trial = s.copy()
        trial[3] += shear * d_gamma
        r = dp_return(*trial, eps_p, bulk, shear, dp)
        s = np.array(r[:4])
        ev_p -= (s[:3].sum() - trial[:3].sum()) / (3 * bulk)
        eps_p += r[5]
        s[:3] += (-300e3 - s[:3].sum()) / 3  # drained at a constant mean stress (servo)
    assert eps_p > 2.0
    n = 1 - 0.6 * math.exp(-ev_p)  # Eq. (8) integrated
    law = porosity_bound(np.array([eps_p]), 0.4, -5.0, 0.5)[0]
    assert (0.4 - n) > 0.1  # it did compact
    assert n == pytest.approx(law, abs=2e-3 * (0.4 - law))


def test_deficit_names_the_particle_below_the_bound():
    snap = {"time": 5.0, "n": np.array([0.40, 0.30, 0.05]), "eps_p": np.array([0.0, 2.0, 2.0]),
            "id": np.array([7, 8, 9])}
    d = porosity_deficit(snap, 0.4, -5.0, 0.5)
    assert d["deficit_id"] == 9 and d["below_bound"] == 1 and d["n_min"] == 0.05

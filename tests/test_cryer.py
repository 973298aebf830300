"""Cryer's sphere, the reference of the 3D scene `cryer` (issue 37): the analytical series
of `psph/verify/cryer.py` against its radial finite-volume solution of the same equations
(`radial_centre_pressure`, set up from the mass balance and equilibrium alone)."""

import numpy as np
import pytest

from psph.verify.cryer import Cryer, radial_centre_pressure


@pytest.mark.parametrize("poisson, bulk_water", [(0.25, 1.0e9), (0.0, 1.0e9), (0.3, 2.0e7)])
def test_centre_pressure_series_matches_a_radial_solution(poisson, bulk_water):
    """The series against the radial solution over tau = 0.01 ... 1 (the Mandel-Cryer rise
    above p0 and the decay), for two Poisson's ratios and a stiff and a soft pore fluid."""
    cryer = Cryer(radius=1.0, load=10.0e3, young=20.0e6, poisson=poisson, porosity=0.4,
                  bulk_water=bulk_water, conductivity=2.0e-4, gamma_l=9810.0)
    taus = np.round(np.concatenate([np.arange(0.01, 0.2, 0.01), np.arange(0.2, 1.01, 0.1)]),
                    4)
    numeric = radial_centre_pressure(cryer, taus)
    series = cryer.centre_pressure(taus * cryer.radius ** 2 / cryer.cv) / cryer.p0
    assert np.max(np.abs(series - numeric)) < 1e-4  # 1.5e-5 to 2.4e-5 measured, O(h^2)
    assert series.max() > 1.05  # the Mandel-Cryer effect
    assert series[-1] < 0.05  # drained by tau = 1


def test_undrained_pressure_and_coefficient():
    """p0 = q / (1 + n K / K_l): all of q with an incompressible fluid; c is Terzaghi's
    c_v of the same soil (k M / gamma_l with an incompressible fluid)."""
    stiff = Cryer(1.0, 1.0e4, 2.0e7, 0.3, 0.4, 1.0e30, 1.0e-4, 9810.0)
    assert stiff.p0 == pytest.approx(1.0e4, rel=1e-12)
    assert stiff.cv == pytest.approx(1.0e-4 * stiff.modulus / 9810.0, rel=1e-12)
    assert stiff.bulk + 4.0 * stiff.shear / 3.0 == pytest.approx(stiff.modulus, rel=1e-12)

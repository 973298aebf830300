"""Cryer's sphere, the reference of the 3D scene `cryer` (issue 37): the analytical series
of `psph/verify/cryer.py` against a radial finite-volume solution of the same equations,
set up here from the mass balance and equilibrium alone.

Radial symmetry makes the displacement irrotational, so equilibrium gives
M e - p = f(t) (e the volumetric strain, uniform f), and the drained surface under the
confining pressure q fixes f = (-q + beta <p>) / (1 - beta), beta = 4 G / (3 M), <p> the
sphere's mean pressure. The mass balance (n / K_l) dp/dt + de/dt = (k / gamma_l) lap p
becomes, in P = p / p0, tau = c t / a^2, r / a:

    dP/dtau + gamma <dP/dtau> = lap P,   gamma = 4 G / (3 K (1 + n M / K_l)),

P = 1 at tau = 0, P = 0 on the surface; solved by Crank-Nicolson on finite volumes.
"""

import numpy as np
import pytest

from psph.verify.cryer import Cryer


def radial_centre_pressure(cryer: Cryer, taus: np.ndarray, cells: int = 300,
                           dtau: float = 1e-4) -> np.ndarray:
    """P at the innermost cell centre (r = a / (2 cells)) at each tau of `taus`."""
    h = 1.0 / cells
    i = np.arange(cells)
    vol = ((i + 1.0) ** 3 - i ** 3) * h ** 3 / 3.0
    weights = vol / vol.sum()  # <P> = weights . P
    area = ((i + 1.0) * h) ** 2  # the outer face of each cell
    lap = np.zeros((cells, cells))
    for k in range(cells - 1):  # the face between cells k and k + 1
        flux = area[k] / h
        lap[k, k] -= flux / vol[k]
        lap[k, k + 1] += flux / vol[k]
        lap[k + 1, k + 1] -= flux / vol[k + 1]
        lap[k + 1, k] += flux / vol[k + 1]
    lap[-1, -1] -= area[-1] / (0.5 * h) / vol[-1]  # P = 0 on the surface, h/2 away
    g = 4.0 * cryer.shear / (3.0 * cryer.bulk * (
        1.0 + cryer.porosity * cryer.modulus / cryer.bulk_water))
    mass = np.eye(cells) + g * np.outer(np.ones(cells), weights)
    step = np.linalg.solve(mass - 0.5 * dtau * lap, mass + 0.5 * dtau * lap)
    p = np.ones(cells)
    out, tau = [], 0.0
    for target in taus:
        while tau < target - 1e-12:
            p = step @ p
            tau += dtau
        out.append(p[0])
    return np.array(out)


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

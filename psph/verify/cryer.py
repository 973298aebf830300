"""Cryer's sphere (Cryer 1963; Verruijt, Theory and Problems of Poroelasticity, Sect. 3.3):
the reference of the 3D scene `cryer`.

A saturated sphere of radius a, its surface drained (p = 0), takes a sudden uniform
confining pressure q at t = 0. With incompressible grains and the pore fluid's storage
n / K_l (psph's mixture, Eq. 5 and 9), the undrained pressure is

    p0 = q / (1 + n K / K_l),

K = E / (3 (1 - 2 nu)) the drained bulk modulus, and the pressure at the centre is

    p(0, t) / p0 = sum_j eta (sin xi_j - xi_j) / ((eta - 1) sin xi_j + eta xi_j cos xi_j / 2)
                   exp(-xi_j^2 c t / a^2),

over the positive roots of (1 - eta xi^2 / 2) tan xi = xi, with

    eta = M / (2 G) (1 + n K / K_l),   c = k / (gamma_l (n / K_l + 1 / M)),

G the shear and M = K + 4 G / 3 the constrained modulus; c is Terzaghi's c_v of the same
soil (`terzaghi.py`). The centre pressure first rises above p0 (the Mandel-Cryer effect:
the drained rim contracts and squeezes the core) before it decays. The series sums to 1 at
t = 0; `radial_centre_pressure` solves the same equations on a radial grid, an independent
check of the series (`tests/test_cryer.py`):

Radial symmetry makes the displacement irrotational, so equilibrium gives M e - p = f(t)
(e the volumetric strain, uniform f), and the drained surface under the confining
pressure q fixes f = (-q + beta <p>) / (1 - beta), beta = 4 G / (3 M), <p> the sphere's
mean pressure. The mass balance (n / K_l) dp/dt + de/dt = (k / gamma_l) lap p becomes, in
P = p / p0, tau = c t / a^2 and r / a,

    dP/dtau + gamma <dP/dtau> = lap P,   gamma = 4 G / (3 K (1 + n M / K_l)),

P = 1 at tau = 0, P = 0 on the surface.
"""

import math
from dataclasses import dataclass

import numpy as np

from psph.physics.material import constrained_modulus


@dataclass(frozen=True)
class Cryer:
    radius: float  # a (m)
    load: float  # q (Pa), the confining pressure
    young: float  # E (Pa)
    poisson: float  # nu
    porosity: float  # n
    bulk_water: float  # K_l (Pa)
    conductivity: float  # k (m/s)
    gamma_l: float  # rho_l g (N/m^3)

    @property
    def bulk(self) -> float:
        """K, the drained bulk modulus (Pa)."""
        return self.young / (3.0 * (1.0 - 2.0 * self.poisson))

    @property
    def shear(self) -> float:
        """G (Pa)."""
        return self.young / (2.0 * (1.0 + self.poisson))

    @property
    def modulus(self) -> float:
        """M = K + 4 G / 3, the constrained modulus (Pa)."""
        return constrained_modulus(self.young, self.poisson)

    @property
    def p0(self) -> float:
        """The undrained pressure right after loading (Pa)."""
        return self.load / (1.0 + self.porosity * self.bulk / self.bulk_water)

    @property
    def eta(self) -> float:
        return self.modulus / (2.0 * self.shear) * (
            1.0 + self.porosity * self.bulk / self.bulk_water)

    @property
    def cv(self) -> float:
        """The consolidation coefficient (m^2/s)."""
        return self.conductivity / (
            self.gamma_l * (self.porosity / self.bulk_water + 1.0 / self.modulus))

    def roots(self, count: int = 200) -> np.ndarray:
        """The first `count` positive roots of (1 - eta xi^2 / 2) sin xi = xi cos xi
        (the tangent form without its poles), by bisection of each sign change."""
        eta = self.eta

        def g(xi):
            return (1.0 - 0.5 * eta * xi * xi) * np.sin(xi) - xi * np.cos(xi)

        # one root in each interval ((k - 1/2) pi, (k + 1/2) pi] for k >= 1 (tan's branches);
        # a fine grid within each finds it whatever eta
        grid = np.linspace(1e-6, (count + 1.5) * math.pi, 64 * (count + 2))
        values = g(grid)
        change = np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[0][:count]
        lo, hi = grid[change], grid[change + 1]
        glo = g(lo)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            gm = g(mid)
            left = np.sign(gm) == np.sign(glo)
            lo = np.where(left, mid, lo)
            glo = np.where(left, gm, glo)
            hi = np.where(left, hi, mid)
        return 0.5 * (lo + hi)

    def coefficients(self, count: int = 200) -> tuple[np.ndarray, np.ndarray]:
        """(xi_j, A_j): p(0, t) / p0 = sum_j A_j exp(-xi_j^2 c t / a^2)."""
        xi = self.roots(count)
        eta = self.eta
        a = eta * (np.sin(xi) - xi) / ((eta - 1.0) * np.sin(xi) + 0.5 * eta * xi * np.cos(xi))
        return xi, a

    def time_factor(self, t):
        """c t / a^2."""
        return np.asarray(t, float) * self.cv / self.radius ** 2

    def centre_pressure(self, t, count: int = 200) -> np.ndarray:
        """p at the centre (Pa) at times t > 0 (s) after the load."""
        xi, a = self.coefficients(count)
        tau = np.atleast_1d(self.time_factor(t))
        return self.p0 * (np.exp(-np.outer(tau, xi * xi)) @ a).reshape(np.shape(t))


def radial_centre_pressure(cryer: Cryer, taus: np.ndarray, cells: int = 300,
                           dtau: float = 1e-4) -> np.ndarray:
    """p / p0 at the innermost cell centre (r = a / (2 cells)) at each tau of `taus`
    (increasing): the equations of the module docstring by Crank-Nicolson on finite
    volumes."""
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


def from_scene(scene) -> Cryer:
    """The sphere of a `cryer` scene: its one [[particles.spheres]], the load on its
    surface, the (first) material."""
    m = scene.material
    return Cryer(radius=scene.particles.spheres[0].radius, load=scene.loads[0].pressure,
                 young=m.E, poisson=m.nu, porosity=m.porosity, bulk_water=m.K_l,
                 conductivity=m.k, gamma_l=m.rho_l * m.g_ref)


def centre_errors(scene, t: np.ndarray, p: np.ndarray) -> dict:
    """The centre probe's pressure history p(t) against the series, timed from the
    middle of the load's ramp: the peak (value and time) of each, and the largest
    difference over p0 after the ramp (the whole curve)."""
    ref = from_scene(scene)
    ramp = scene.loads[0].ramp
    after = t > ramp
    if not after.any():
        return {"reference": "Cryer's series at the centre (psph.verify.cryer)",
                "p0_Pa": ref.p0, "cv_m2_per_s": ref.cv,
                "note": f"the run ended within the load's ramp ({ramp:g} s): no peak yet"}
    ts = t[after] - 0.5 * ramp
    pa = ref.centre_pressure(ts)
    k, ka = int(np.argmax(p[after])), int(np.argmax(pa))
    dense = np.linspace(1e-4, 0.3, 3000) / ref.cv * ref.radius ** 2
    pd = ref.centre_pressure(dense)
    kd = int(np.argmax(pd))
    peak, peak_ref = float(p[after][k]), float(pd[kd])
    return {"reference": "Cryer's series at the centre (psph.verify.cryer)",
            "p0_Pa": ref.p0, "cv_m2_per_s": ref.cv,
            "peak_over_p0": peak / ref.p0, "reference_peak_over_p0": peak_ref / ref.p0,
            "peak_error": peak / peak_ref - 1.0,
            "peak_time_s": float(ts[k]), "reference_peak_time_s": float(dense[kd]),
            "peak_time_error": float(ts[k] / dense[kd] - 1.0),
            "reference_peak_time_sampled_s": float(ts[ka]),
            "max_abs_error_over_p0": float(np.max(np.abs(p[after] - pa)) / ref.p0),
            "time_factor_end": float(ref.time_factor(ts[-1]))}

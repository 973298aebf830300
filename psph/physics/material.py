"""Material constants derived from the scene (Section 2.2, 3.3-3.5)."""

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ElasticSoil:
    E: float
    nu: float
    rho_s: float
    rho_l: float
    K_l: float
    gamma_l: float
    porosity: float
    conductivity: float

    @property
    def shear(self) -> float:
        return self.E / (2 * (1 + self.nu))

    @property
    def lam(self) -> float:
        return self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))

    @property
    def constrained_modulus(self) -> float:
        return self.lam + 2 * self.shear

    @property
    def sound_speed(self) -> float:
        """c_sp = sqrt(E / rho_s), Eq. (41); also the artificial-viscosity sound speed."""
        return math.sqrt(self.E / self.rho_s)

    @property
    def undrained_sound_speed(self) -> float:
        """c_sp = sqrt((K_l / n + 4 G / 3) / (n rho_l + n_s rho_s)), Eq. (28)."""
        return math.sqrt((self.K_l / self.porosity + 4.0 * self.shear / 3.0)
                         / self.mixture_density)

    def damping_coefficient(self, eta_d: float, h: float) -> float:
        """c_d = eta_d sqrt(E / (rho_s h^2)), Eq. (44) (1/s)."""
        return eta_d * math.sqrt(self.E / (self.rho_s * h * h))

    @property
    def mixture_density(self) -> float:
        n = self.porosity
        return (1 - n) * self.rho_s + n * self.rho_l


def plasticity_parameters(scene) -> np.ndarray:
    """(phi_p, phi_r, c_p, c_r, psi_0, eta, s_f) for the kernels, angles in radians
    (Eq. 17-19); zeros for an elastic material."""
    pl = scene.material.plasticity
    if pl is None:
        return np.zeros(7)
    phi_r = pl.phi if pl.phi_r is None else pl.phi_r
    c_r = pl.c if pl.c_r is None else pl.c_r
    return np.array([math.radians(pl.phi), math.radians(phi_r), pl.c, c_r,
                     math.radians(pl.psi), pl.eta, pl.s_f])


def soil_from_scene(scene) -> ElasticSoil:
    m = scene.material
    return ElasticSoil(E=m.E, nu=m.nu, rho_s=m.rho_s, rho_l=m.rho_l, K_l=m.K_l,
                       gamma_l=m.rho_l * m.g_ref, porosity=m.porosity, conductivity=m.k)

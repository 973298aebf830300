"""Material constants derived from the scene (Section 2.2, 3.3-3.5)."""

import math
from dataclasses import dataclass

import numpy as np

from psph.kernels.update import (
    MAT_BULK3,
    MAT_C_K,
    MAT_COLUMNS,
    MAT_DP,
    MAT_K,
    MAT_LAM,
    MAT_MOHR_COULOMB,
    MAT_N_MIN,
    MAT_NL_LENGTH,
    MAT_NL_M,
    MAT_PLASTIC,
    MAT_RHO_S,
    MAT_SHEAR,
    MAT_TENSION,
)


def lame(E: float, nu: float) -> tuple[float, float]:
    """Lame's lambda and the shear modulus G of Young's modulus E and Poisson's ratio nu
    (Eq. 8's isotropic elasticity): the one place psph derives them."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def constrained_modulus(E: float, nu: float) -> float:
    """M = lambda + 2 G, the oedometric (laterally confined) modulus."""
    lam, shear = lame(E, nu)
    return lam + 2 * shear


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
        return lame(self.E, self.nu)[1]

    @property
    def lam(self) -> float:
        return lame(self.E, self.nu)[0]

    @property
    def constrained_modulus(self) -> float:
        return constrained_modulus(self.E, self.nu)

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


def plasticity_parameters(scene, material=None) -> np.ndarray:
    """(phi_p, phi_r, c_p, c_r, psi_0, eta, s_f) for the kernels, angles in radians
    (Eq. 17-19); zeros for an elastic material. `material`: default the scene's first."""
    pl = (scene.material if material is None else material).plasticity
    if pl is None:
        return np.zeros(7)
    phi_r = pl.phi if pl.phi_r is None else pl.phi_r
    c_r = pl.c if pl.c_r is None else pl.c_r
    return np.array([math.radians(pl.phi), math.radians(phi_r), pl.c, c_r,
                     math.radians(pl.psi), pl.eta, pl.s_f])


def soil_from_scene(scene, material=None) -> ElasticSoil:
    """The constants of one material (default: the first; its fluid is every one's)."""
    m = scene.material if material is None else material
    return ElasticSoil(E=m.E, nu=m.nu, rho_s=m.rho_s, rho_l=m.rho_l, K_l=m.K_l,
                       gamma_l=m.rho_l * m.g_ref, porosity=m.porosity, conductivity=m.k)


def tension_cutoff(material) -> float:
    """The cap on the mean effective stress (Pa, tension positive) of `dp_return`: the
    material's `plasticity.tension_cutoff`, inf without one (the apex of Eq. 14)."""
    pl = material.plasticity
    return math.inf if pl is None or pl.tension_cutoff is None else pl.tension_cutoff


def material_table(scene) -> np.ndarray:
    """(n_materials, MAT_COLUMNS) float64: the row of each material, indexed by the
    particle field `material`, in the column layout of psph/kernels/update.py (MAT_*):
    Lame constants and 3K = 3 lambda + 2 mu (Eq. 11), rho_s (Eq. 24 with Eq. 8), k and
    C_k of Eq. (4), the porosity floor, 1 for a Drucker-Prager material and its
    (phi_p, phi_r, c_p, c_r, psi_0, eta, s_f) of Eq. (17)-(19), with l_c and m of its
    non-local softening strain (0: local; issue 17), its tension cut-off (inf: none;
    issue 13) and 1 for the Lode-dependent Mohr-Coulomb cone (issue 37). The values are
    the same floats as the scalars the kernels took before several materials (issue
    16)."""
    mats = scene.material_list
    table = np.zeros((len(mats), MAT_COLUMNS))
    for i, m in enumerate(mats):
        s = soil_from_scene(scene, m)
        table[i, MAT_LAM] = s.lam
        table[i, MAT_SHEAR] = s.shear
        table[i, MAT_BULK3] = 3.0 * s.lam + 2.0 * s.shear
        table[i, MAT_RHO_S] = m.rho_s
        table[i, MAT_K] = m.k
        table[i, MAT_C_K] = m.C_k
        table[i, MAT_N_MIN] = m.porosity_min
        table[i, MAT_PLASTIC] = 1.0 if m.model == "drucker_prager" else 0.0
        table[i, MAT_DP:MAT_DP + 7] = plasticity_parameters(scene, m)
        table[i, MAT_TENSION] = tension_cutoff(m)
        if m.plasticity is not None and m.plasticity.surface == "mohr_coulomb":
            table[i, MAT_MOHR_COULOMB] = 1.0
        reg = m.plasticity.regularisation if m.plasticity is not None else None
        if reg is not None:
            table[i, MAT_NL_LENGTH] = reg.length
            table[i, MAT_NL_M] = reg.m
    return table


def stiffest(scene) -> ElasticSoil:
    """The material with the fastest solid wave sqrt(E / rho_s) of Eq. (41): the
    artificial viscosity's sound speed and the damping coefficient of Eq. (44) are taken
    from it (one value for every pair and particle, the largest over the materials; the
    first material when it is the only one). Ties: the first."""
    mats = scene.material_list
    speeds = [math.sqrt(m.E / m.rho_s) for m in mats]
    return soil_from_scene(scene, mats[speeds.index(max(speeds))])


def fastest_undrained(scene) -> float:
    """The largest undrained c_sp of Eq. (28) over the materials."""
    return max(soil_from_scene(scene, m).undrained_sound_speed for m in scene.material_list)


def material_row(lam: float = 0.0, shear: float = 0.0, rho_s: float = 0.0, k: float = 0.0,
                 c_k: float = 0.0, n_min: float = 0.0, dp: np.ndarray | None = None,
                 bulk3: float | None = None, tension: float = math.inf) -> np.ndarray:
    """A one-material table (1, MAT_COLUMNS) from constants, for kernels called outside a
    run (the element tests, unit tests); dp: the 7 Drucker-Prager parameters or None
    (elastic); bulk3 default 3 lambda + 2 mu; tension: the cut-off of sigma'_m."""
    row = np.zeros((1, MAT_COLUMNS))
    row[0, [MAT_LAM, MAT_SHEAR, MAT_RHO_S, MAT_K, MAT_C_K, MAT_N_MIN]] = \
        (lam, shear, rho_s, k, c_k, n_min)
    row[0, MAT_BULK3] = 3.0 * lam + 2.0 * shear if bulk3 is None else bulk3
    if dp is not None:
        row[0, MAT_PLASTIC] = 1.0
        row[0, MAT_DP:MAT_DP + 7] = dp
    row[0, MAT_TENSION] = tension
    return row

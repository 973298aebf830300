"""Material constants derived from the scene (Sections 2.2 and 3.3-3.5 of Lian et al.
2023): the elastic constants of Eq. (11), the sound speeds of Eq. (28) and (41), the
damping of Eq. (44), and the per-material table the kernels index (`material_table`)."""

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
    """Lame's lambda and the shear modulus G of the isotropic elasticity D^e of Eq. (11):
    the one place psph derives them.

    Parameters
    ----------
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio.

    Returns
    -------
    lam, shear : float
        lambda and G (Pa).
    """
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def constrained_modulus(E: float, nu: float) -> float:
    """M = lambda + 2 G, the oedometric (laterally confined) modulus.

    Parameters
    ----------
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio.

    Returns
    -------
    float
        M (Pa).
    """
    lam, shear = lame(E, nu)
    return lam + 2 * shear


@dataclass(frozen=True)
class ElasticSoil:
    """One material's constants: E, K_l (Pa), rho_s, rho_l (kg/m^3), gamma_l (N/m^3),
    porosity, hydraulic conductivity (m/s)."""

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
        """Shear modulus G (Pa)."""
        return lame(self.E, self.nu)[1]

    @property
    def lam(self) -> float:
        """Lame's lambda (Pa)."""
        return lame(self.E, self.nu)[0]

    @property
    def constrained_modulus(self) -> float:
        """M = lambda + 2 G (Pa)."""
        return constrained_modulus(self.E, self.nu)

    @property
    def sound_speed(self) -> float:
        """c_sp = sqrt(E / rho_s) of Eq. (41) (m/s); also the artificial-viscosity sound
        speed."""
        return math.sqrt(self.E / self.rho_s)

    @property
    def undrained_sound_speed(self) -> float:
        """c_sp = sqrt((K_l / n + 4 G / 3) / (n rho_l + n_s rho_s)) of Eq. (28) (m/s)."""
        return math.sqrt((self.K_l / self.porosity + 4.0 * self.shear / 3.0)
                         / self.mixture_density)

    def damping_coefficient(self, eta_d: float, h: float) -> float:
        """The damping coefficient c_d = eta_d sqrt(E / (rho_s h^2)) of Eq. (44).

        Parameters
        ----------
        eta_d : float
            damping ratio eta_d (dimensionless).
        h : float
            smoothing length (m).

        Returns
        -------
        float
            c_d (1/s).
        """
        return eta_d * math.sqrt(self.E / (self.rho_s * h * h))

    @property
    def mixture_density(self) -> float:
        """(1 - n) rho_s + n rho_l (kg/m^3)."""
        n = self.porosity
        return (1 - n) * self.rho_s + n * self.rho_l


def plasticity_parameters(scene, material=None) -> np.ndarray:
    """The softening parameters of Eq. (17)-(19) for the kernels.

    Parameters
    ----------
    scene : Scene
        the validated scene.
    material : Material, optional
        default the scene's first.

    Returns
    -------
    (7,) float64 array
        (phi_p, phi_r, c_p, c_r, psi_0, eta, s_f), angles in rad, cohesions in Pa; zeros
        for an elastic material.
    """
    pl = (scene.material if material is None else material).plasticity
    if pl is None:
        return np.zeros(7)
    phi_r = pl.phi if pl.phi_r is None else pl.phi_r
    c_r = pl.c if pl.c_r is None else pl.c_r
    return np.array([math.radians(pl.phi), math.radians(phi_r), pl.c, c_r,
                     math.radians(pl.psi), pl.eta, pl.s_f])


def soil_from_scene(scene, material=None) -> ElasticSoil:
    """The constants of one material.

    Parameters
    ----------
    scene : Scene
        the validated scene.
    material : Material, optional
        default the first (whose pore fluid is every material's).

    Returns
    -------
    ElasticSoil
    """
    m = scene.material if material is None else material
    return ElasticSoil(E=m.E, nu=m.nu, rho_s=m.rho_s, rho_l=m.rho_l, K_l=m.K_l,
                       gamma_l=m.rho_l * m.g_ref, porosity=m.porosity, conductivity=m.k)


def tension_cutoff(material) -> float:
    """The cap on the mean effective stress of `dp_return`.

    Parameters
    ----------
    material : Material
        a scene material.

    Returns
    -------
    float
        its `plasticity.tension_cutoff` (Pa, tension positive); inf without one (the apex
        of Eq. 14 bounds sigma'_m).
    """
    pl = material.plasticity
    return math.inf if pl is None or pl.tension_cutoff is None else pl.tension_cutoff


def material_table(scene) -> np.ndarray:
    """The material table the kernels index by the particle field `material`.

    Parameters
    ----------
    scene : Scene
        the validated scene.

    Returns
    -------
    (n_materials, MAT_COLUMNS) float64 array
        one row a material in the column layout of psph/kernels/update.py (MAT_*): Lame
        constants and 3K = 3 lambda + 2 mu (Eq. 11; Pa), rho_s (Eq. 24 with Eq. 8;
        kg/m^3), k (m/s) and C_k of Eq. (4), the porosity floor, 1 for a Drucker-Prager
        material and its (phi_p, phi_r, c_p, c_r, psi_0, eta, s_f) of Eq. (17)-(19), l_c
        (m) and m of its non-local softening strain (0: local), its tension cut-off (Pa;
        inf: none) and 1 for the Lode-dependent Mohr-Coulomb cone.
    """
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


def material_tables_of_trigger(scene, table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The material tables before and after the scene's `[trigger]`.

    Before it, the soil does not soften (eta = 0 of Eq. 17-19: the gravity loading at peak
    strength); after it, c_p and tan(phi_p), and unless `reduce_residual = false` c_r and
    tan(phi_r), are divided by `strength_factor`, and eta is the material's.

    Parameters
    ----------
    scene : Scene
        the validated scene, with `trigger` set.
    table : (n_materials, MAT_COLUMNS) float64 array
        the scene's material table (`material_table`).

    Returns
    -------
    before, after : (n_materials, MAT_COLUMNS) float64 arrays
        new tables.
    """
    tr = scene.trigger
    f = tr.strength_factor
    before, after = table.copy(), table.copy()
    before[:, MAT_DP + 5] = 0.0
    reduce = [0, 2] + ([1, 3] if tr.reduce_residual else [])
    for c in reduce:
        col = after[:, MAT_DP + c]
        if c in (0, 1):  # friction angles (rad): tan(phi) / f
            after[:, MAT_DP + c] = np.arctan(np.tan(col) / f)
        else:  # cohesions (Pa)
            after[:, MAT_DP + c] = col / f
    return before, after


def stiffest(scene) -> ElasticSoil:
    """The material with the fastest solid wave sqrt(E / rho_s) of Eq. (41): the
    artificial viscosity's sound speed and the damping coefficient of Eq. (44) are taken
    from it (one value for every pair and particle, the largest over the materials; the
    first material when it is the only one). Ties: the first.

    Parameters
    ----------
    scene : Scene
        the validated scene.

    Returns
    -------
    ElasticSoil
    """
    mats = scene.material_list
    speeds = [math.sqrt(m.E / m.rho_s) for m in mats]
    return soil_from_scene(scene, mats[speeds.index(max(speeds))])


def fastest_undrained(scene) -> float:
    """The largest undrained sound speed c_sp of Eq. (28) over the materials.

    Parameters
    ----------
    scene : Scene
        the validated scene.

    Returns
    -------
    float
        c_sp (m/s).
    """
    return max(soil_from_scene(scene, m).undrained_sound_speed for m in scene.material_list)


def material_row(lam: float = 0.0, shear: float = 0.0, rho_s: float = 0.0, k: float = 0.0,
                 c_k: float = 0.0, n_min: float = 0.0, dp: np.ndarray | None = None,
                 bulk3: float | None = None, tension: float = math.inf) -> np.ndarray:
    """A one-material table from constants, for kernels called outside a run (the element
    tests, unit tests).

    Parameters
    ----------
    lam, shear : float
        Lame constants lambda and mu (Pa).
    rho_s : float
        grain density (kg/m^3).
    k : float
        hydraulic conductivity (m/s).
    c_k : float
        C_k of Eq. (4); 0: constant k.
    n_min : float
        porosity floor (0: none).
    dp : (7,) float64 array, optional
        the Drucker-Prager parameters of `plasticity_parameters`; None: elastic.
    bulk3 : float, optional
        3K (Pa), default 3 lambda + 2 mu.
    tension : float
        the cut-off of sigma'_m (Pa); inf: none.

    Returns
    -------
    (1, MAT_COLUMNS) float64 array
    """
    row = np.zeros((1, MAT_COLUMNS))
    row[0, [MAT_LAM, MAT_SHEAR, MAT_RHO_S, MAT_K, MAT_C_K, MAT_N_MIN]] = \
        (lam, shear, rho_s, k, c_k, n_min)
    row[0, MAT_BULK3] = 3.0 * lam + 2.0 * shear if bulk3 is None else bulk3
    if dp is not None:
        row[0, MAT_PLASTIC] = 1.0
        row[0, MAT_DP:MAT_DP + 7] = dp
    row[0, MAT_TENSION] = tension
    return row

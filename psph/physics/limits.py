"""The time-step limits of a scene: Eq. (41) for the solid and for the undrained wave of
the explicit update, Eq. (42) for the fluid, and TPI's measured stability bound (the gain
G of Eq. 38). Used by the scene's validation (`psph/config/rules.py`) and the stepping
(`psph/solver/stepping.py`). `scene` is a validated `psph.config.schema.Scene`, which
validates itself with these limits: it is not imported here (physics sits below the
scene's schema)."""

import math

from psph.physics.material import constrained_modulus


def solid_dt_limit(scene) -> float:
    """Delta t_s of Eq. (41): C_s h / c_sp with c_sp = sqrt(E / rho_s), of the material
    with the fastest c_sp (the most restrictive) when there are several.

    Parameters
    ----------
    scene : psph.config.schema.Scene
        The validated scene (its materials, h (m), Courant numbers and gravity).

    Returns
    -------
    float
        The step limit (s).
    """
    return min(scene.time.cfl_solid * scene.h / math.sqrt(m.E / m.rho_s)
               for m in scene.material_list)


def undrained_dt_limit(scene) -> float:
    """Eq. (41) with the undrained P-wave speed of the explicit coupled update,
    c_u = sqrt((lambda + 2 G + K_l / n) / rho): with explicit Eq. (25) the pore water
    adds the stiffness K_l / n to the solid's (measured: the sensitive clay slope of
    Section 4.5, K_l / n = 20 E, blows up at 2.5e-4 s and runs at 1e-4 s). Several
    materials: the most restrictive.

    Parameters
    ----------
    scene : psph.config.schema.Scene
        The validated scene (its materials, h (m), Courant numbers and gravity).

    Returns
    -------
    float
        The step limit (s).
    """
    return min(_undrained_dt(scene, m) for m in scene.material_list)


def _undrained_dt(scene, m) -> float:
    rho = (1 - m.porosity) * m.rho_s + m.porosity * m.rho_l
    c_u = math.sqrt((constrained_modulus(m.E, m.nu) + m.K_l / m.porosity) / rho)
    return scene.time.cfl_solid * scene.h / c_u


TPI_ALPHA_MAX = 0.75


def tpi_dt(scene) -> float:
    """The TPI step: time.dt, or R times Eq. (42) capped by the solid limit Eq. (41) and by
    TPI's own stability bound (`tpi_gain_dt_limit`).

    Parameters
    ----------
    scene : psph.config.schema.Scene
        The validated scene (its materials, h (m), Courant numbers and gravity).

    Returns
    -------
    float
        The step (s).
    """
    if scene.time.dt is not None:
        return scene.time.dt
    return min(solid_dt_limit(scene), scene.pressure.R * fluid_dt_limit(scene),
               tpi_gain_dt_limit(scene))


def tpi_gain_dt_limit(scene) -> float:
    """The largest dt with G = dt gamma_l / (rho k) within `tpi_gain_limit`.

    Parameters
    ----------
    scene : psph.config.schema.Scene
        The validated scene (its materials, h (m), Courant numbers and gravity).

    Returns
    -------
    float
        The step limit (s).
    """
    gravity = any(g != 0.0 for g in scene.gravity)
    return tpi_gain_limit(scene.pressure.alpha, gravity) / tpi_gain(scene, 1.0)


def tpi_gain(scene, dt: float) -> float:
    """G = dt gamma_l / (rho k): Eq. (38) has no storage, so p answers div v at once with
    the gain gamma_l / sum_j A_ij (~ h^2 / k) and grad p feeds back into v, an explicit
    bulk viscosity whose step limit is rho k / gamma_l, independent of h (measured by
    bench/verification/tpi_gravity.py). rho: the mixture density; k: the initial one;
    several materials: the largest G (the most restrictive).

    Parameters
    ----------
    scene : psph.config.schema.Scene
        The validated scene (its materials, h (m), Courant numbers and gravity).
    dt : float
        The time step (s).

    Returns
    -------
    float
        G (dimensionless).
    """
    return max(dt * m.rho_l * m.g_ref / (((1 - m.porosity) * m.rho_s + m.porosity * m.rho_l)
                                         * m.k) if m.k > 0.0 else math.inf
               for m in scene.material_list)


def tpi_gain_limit(alpha: float, gravity: bool = True) -> float:
    """The largest stable G, fitted to the maps of bench/verification/tpi_gravity.py (alpha
    0 to 0.7): under gravity (the geostatic column at rest, G 0.2 to 1.2) 1.15 (1 - alpha);
    without it (the loaded Terzaghi column through its drained switch, G 0.2 to 3.6) 5 (1 -
    alpha)^2, at most 3.6, the largest G measured (stable at alpha = 0).

    Parameters
    ----------
    alpha : float
        TPI's weight alpha of Eq. (39) (dimensionless).
    gravity : bool
        Whether the scene has gravity.

    Returns
    -------
    float
        The largest stable G (dimensionless).
    """
    if gravity:
        return 1.15 * (1.0 - alpha)
    return min(5.0 * (1.0 - alpha) ** 2, 3.6)


def fluid_dt_limit(scene) -> float:
    """Delta t_l of Eq. (42): C_l n gamma_l h^2 / (K_l k); several materials: the most
    restrictive; inf where no water flows (k = 0).

    Parameters
    ----------
    scene : psph.config.schema.Scene
        The validated scene (its materials, h (m), Courant numbers and gravity).

    Returns
    -------
    float
        The step limit (s).
    """
    return min(scene.time.cfl_fluid * m.porosity * (m.rho_l * m.g_ref) * scene.h**2
               / (m.K_l * m.k) if m.k > 0.0 else math.inf for m in scene.material_list)

"""Kernels of the pressure projection (`pressure.scheme = "projection"`).

After the kick v* = v^n + dt a^n (a^n with the pore pressure p^n), the increment
dp = p^(n+1) - p^n solves the mass balance Eq. (29) at n+1 with the fluid storage kept,

    n / (K_l dt) dp - div((k / gamma_l + dt / rho) grad dp) = div(k grad(p^n + psi)) / gamma_l
                                                             - div v*,

where the dt / rho part is the divergence of the velocity correction
v^(n+1) = v* - (dt / rho) grad dp (an approximate projection: the operator is the SPH
Laplacian of `laplacian.py`, the correction the pair-symmetric gradient of Eq. 26).
The right-hand side is the explicit rate of Eq. (25) of Lian et al. (2023) times n / K_l.

The one-sweep step (`time.integrator = "euler"`) takes v* = v^n, the velocity of the
step's sweep, corrects it, and kicks with a^n after: v^(n+1) = v^n - (dt / rho) grad dp +
dt a^n. For the undrained wave (rho dv/dt = -dp/dx, dp/dt = -K dv/dx, a = (c k dt)^2)
its amplification matrix on (v, dt k p / rho) is [[1/(1+a), -1], [a/(1+a), 1]]: determinant
1, trace 1 + 1/(1+a) < 2, so |lambda| = 1 at any dt: stable and undamped. With the kick
first it is [[1, -1], [a, 1]] / (1+a), |lambda|^2 = 1 / (1+a): stable and damped.
"""

import numba as nb
import numpy as np

from psph.kernels.bundles import FluidParams
from psph.kernels.free_surface import on_free_surface
from psph.kernels.interactions import symmetric_gradient_sums
from psph.kernels.kinematics import inverse_moment_3d
from psph.kernels.sum_columns import (
    GP_X,
    GP_Y,
    GS_XX,
    GS_XY,
    GS_YX,
    GS_YY,
    GV_XX,
    GV_XY,
    GV_YX,
    GV_YY,
    M_XX,
    Q_X,
    Q_Y,
    SUM_APSI,
    sum_layout,
)
from psph.kernels.update import _inverse_moment

NSUMS_3D = sum_layout(3).NSUMS


def make_projection_rhs(dim: int):
    """`projection_rhs` in `dim` = 2 or 3 dimensions (one source, `dims.py`).

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `projection_rhs`.
    """
    lay = sum_layout(dim)
    cm, cgv, cgs, cgp, cq = lay.M, lay.GV, lay.GS, lay.GP, lay.Q
    ca, cap_, capsi = lay.SUM_A, lay.SUM_AP, lay.SUM_APSI

    @nb.njit(cache=True, error_model="numpy")
    def projection_rhs(n_owned: int, sums: np.ndarray, p: np.ndarray, perm: np.ndarray,
                       vol: np.ndarray, poro: np.ndarray, fluid: FluidParams, dt: float,
                       storage: np.ndarray, rhs: np.ndarray) -> None:
        """The storage and right-hand side of the projection's solve: storage_i =
        n_i / (K_l dt) and rhs_i = V_i (lap_i / gamma_l - div v*_i), with lap the corrected
        Darcy term of Eq. (23) at p^n (as in the explicit Eq. 25) and div v* from the
        velocity sums (Gv + Gs with M^-1, Eq. 22) of the kicked velocity (symplectic step)
        or of v^n, the step's sweep (the one-sweep step).

        Parameters
        ----------
        n_owned : int
            owned rows 0..n_owned-1.
        sums : (cap, nsums) float64 array
            the pair sums of `interactions.pair_sums`.
        p : (cap,) float64 array
            pore pressure p^n (Pa).
        perm : (cap,) float64 array
            hydraulic conductivity k (m/s).
        vol : (cap,) float64 array
            particle volumes (m^3; m^2 per unit thickness in 2D).
        poro : (cap,) float64 array
            porosity n.
        fluid : `bundles.FluidParams`
            pore-water density rho_l (kg/m^3), unit weight of water gamma_l = rho_l g
            (N/m^3), bulk modulus of water bulk_water = K_l (Pa) and body force b0, b1, b2
            (m/s^2; b2 in 3D only).
        dt : float
            time step (s).
        storage : (cap,) float64 array
            receives n / (K_l dt) (1/(Pa s)).
        rhs : (cap,) float64 array
            receives the right-hand side (m^3/s; m^2/s in 2D).
        """
        rho_l, gamma_l, bulk_water = fluid.rho_l, fluid.gamma_l, fluid.bulk_water
        b0, b1, b2 = fluid.b0, fluid.b1, fluid.b2
        for i in range(n_owned):
            s = sums[i]
            if dim == 2:
                m00, m01, m10, m11 = _inverse_moment(s)
                div_v = ((s[GV_XX] + s[GS_XX]) * m00 + (s[GV_XY] + s[GS_XY]) * m10
                         + (s[GV_YX] + s[GS_YX]) * m01 + (s[GV_YY] + s[GS_YY]) * m11)
                gp0 = s[GP_X] * m00 + s[GP_Y] * m10
                gp1 = s[GP_X] * m01 + s[GP_Y] * m11
                e_i = perm[i] * (gp0 * s[Q_X] + gp1 * s[Q_Y])
                head = s[SUM_APSI] + perm[i] * rho_l * (b0 * s[Q_X] + b1 * s[Q_Y])
            else:
                mi = inverse_moment_3d(s, cm)
                div_v = 0.0
                for a in range(3):
                    for n in range(3):
                        div_v += (s[cgv + 3 * a + n] + s[cgs + 3 * a + n]) * mi[3 * n + a]
                e_i = 0.0
                for m in range(3):
                    gpm = s[cgp] * mi[m] + s[cgp + 1] * mi[3 + m] + s[cgp + 2] * mi[6 + m]
                    e_i += gpm * s[cq + m]
                e_i *= perm[i]
                head = s[capsi] + perm[i] * rho_l * (b0 * s[cq] + b1 * s[cq + 1]
                                                     + b2 * s[cq + 2])
            lap = s[cap_] - p[i] * s[ca] - e_i + head
            storage[i] = poro[i] / (bulk_water * dt)
            rhs[i] = vol[i] * (lap / gamma_l - div_v)

    return projection_rhs


projection_rhs = make_projection_rhs(2)
projection_rhs_3d = make_projection_rhs(3)


@nb.njit(cache=True)
def imposed_increments(n_owned: int, sums: np.ndarray, drained_from: np.ndarray, t: float,
                       drained_surface: bool, p: np.ndarray, out: np.ndarray) -> None:
    """Where p^(n+1) = 0 is imposed: drained from time t on, or a free-surface particle
    when the surface is drained (`free_surface.on_free_surface`, as in `advance`).

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    sums : (cap, nsums) float64 array
        the pair sums, 2D layout or 3D layout (57 columns); M starts at column 0 in both.
    drained_from : (cap,) float64 array
        time from which p = 0 is imposed (s; inf: never).
    t : float
        time of the step's end (s).
    drained_surface : bool
        the free surface is drained.
    p : (cap,) float64 array
        pore pressure p^n (Pa).
    out : (cap, 2) float64 array
        receives (1, -p_i) on imposed rows (the increment that brings p to 0, Pa), else
        (0, 0).
    """
    dim = 3 if sums.shape[1] == NSUMS_3D else 2
    for i in range(n_owned):
        s = sums[i]
        # M starts at column M_XX = 0 in the 2D and the 3D layout alike
        if drained_from[i] <= t or (drained_surface and on_free_surface(s, M_XX, dim)):
            out[i, 0] = 1.0
            out[i, 1] = -p[i]
        else:
            out[i, 0] = 0.0
            out[i, 1] = 0.0


@nb.njit(cache=True)
def mirror_to_ghosts(n_real: int, n_total: int, src: np.ndarray, sign: np.ndarray,
                     field: np.ndarray) -> None:
    """Ghost rows take sign times the value of the row they mirror: a pressure increment
    has no hydrostatic shift, and changes sign across a drained wall (`ghosts.py`).

    Parameters
    ----------
    n_real, n_total : int
        the ghost rows are n_real..n_total-1.
    src : (cap,) int64 array
        each ghost's source row.
    sign : (cap,) float64 array
        +1, or -1 across a drained wall.
    field : (cap, ncomp) float64 array
        the field (any unit); ghost rows are written.
    """
    for g in range(n_real, n_total):
        for c in range(field.shape[1]):
            field[g, c] = sign[g] * field[src[g], c]


@nb.njit(cache=True, error_model="numpy")
def pressure_correction(n_owned: int, n_pairs: int, pairs: np.ndarray, pair_g: np.ndarray,
                        vol: np.ndarray, rho: np.ndarray, dp: np.ndarray, dt: float,
                        norm: float, dv: np.ndarray, v: np.ndarray, acc: np.ndarray) -> None:
    """The projection's velocity correction: v_i += dt a_i and acc_i += a_i with
    a_i = -norm sum_j V_j (dp_i + dp_j) grad_i W_ij / rho_i, the pore-pressure part of
    Eq. (26) for the increment, over the recorded pairs; 2D or 3D by v.

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    n_pairs : int
        number of recorded pairs.
    pairs : (>= n_pairs, 2) int64 array
        the pairs (a, b) of `interactions.pair_sums`.
    pair_g : (>= n_pairs, dim) float64 array
        grad_a W_ab (1/m^(dim+1)).
    vol : (cap,) float64 array
        particle volumes (m^3; m^2 per unit thickness in 2D).
    rho : (cap,) float64 array
        mixture density (kg/m^3).
    dp : (cap,) float64 array
        pressure increment p^(n+1) - p^n (Pa).
    dt : float
        time step (s).
    norm : float
        1 / the lattice moment (`laplacian.lattice_moment`), as the step's stress
        divergence.
    dv : (cap, dim) float64 array
        scratch for the gradient sums.
    v : (cap, dim) float64 array
        velocity (m/s), corrected.
    acc : (cap, dim) float64 array
        acceleration (m/s^2), corrected.
    """
    symmetric_gradient_sums(n_owned, n_pairs, pairs, pair_g, vol, dp, dv)
    for i in range(n_owned):
        for d in range(v.shape[1]):
            a = -norm * dv[i, d] / rho[i]
            acc[i, d] += a
            v[i, d] += dt * a

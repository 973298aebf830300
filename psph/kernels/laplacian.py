"""Matrix-free SPH Laplacian over the pairs recorded by `pair_sums`, for the pressure solve
of the projection scheme.

    (L q)_i = sum_j V_j w_ij 2F_ij (q_j - q_i)

is the Laplacian of Eq. (23) without its first-order correction term, with a pair weight
w_ij (kbar_ij / gamma_l for the Darcy flow of Eq. (29), plus dt / rhobar_ij for the
velocity correction of a projection). Multiplied by V_i it is symmetric, so the operator

    (S q)_i = V_i s_i q_i - V_i (L q)_i,    s_i >= 0 (the storage n / (K_l dt))

is symmetric positive semi-definite, definite once s > 0 or a value is imposed somewhere:
what conjugate gradients need. Imposed rows (`fixed`, e.g. drained particles) are diagonal
rows; their couplings to free rows go to the right-hand side (`fixed_rhs`), which keeps S
symmetric.

The sums follow the recorded pair order, the order `pair_sums` visits, so they are as
partition-independent as its sums (1 vs 2 ranks bitwise).
"""

import math

import numba as nb
import numpy as np

from psph.kernels.spline import dw_cubic, dw_cubic_dim


def lattice_moment(dx: float, h: float, dim: int = 2) -> float:
    """The lattice moment m0 = sum_j V_j (-W'(r_ij) / r_ij) y_ij^2 over a full square
    (cubic, dim = 3) lattice: the moment matrix M of Eq. (22) of an interior particle of
    the initial lattice is m0 I (0.991 at h = 1.2 dx).

    Eq. (23) takes F~ with the normalised gradient M^-1 grad W; with the plain gradient the
    Laplacian of a quadratic comes out m0 times too small, and the consolidation with it
    (Terzaghi's excess pressure 1 % of q too high at depth). The stress divergence of
    Eq. (26) has the same factor: a uniform stress under a surface load q balances m0 q.
    The Darcy sums, the stress divergence and the projection's operator and velocity
    correction are therefore divided by m0 (`Simulation._interactions`, `PressureSolve`).

    Parameters
    ----------
    dx : float
        lattice spacing (m).
    h : float
        smoothing length (m).
    dim : int
        2 or 3.

    Returns
    -------
    float
        m0 (dimensionless).
    """
    n = int(np.ceil(2.0 * h / dx))
    m = 0.0
    if dim == 2:
        for i in range(-n, n + 1):
            for j in range(-n, n + 1):
                r = dx * np.hypot(i, j)
                if 0.0 < r < 2.0 * h:
                    m += dx * dx * (-dw_cubic(r, h) / r) * (j * dx) ** 2
        return m
    for i in range(-n, n + 1):
        for j in range(-n, n + 1):
            for k in range(-n, n + 1):
                r = dx * math.sqrt(i * i + j * j + k * k)
                if 0.0 < r < 2.0 * h:
                    m += dx ** 3 * (-dw_cubic_dim(r, h, 3) / r) * (j * dx) ** 2
    return m


def make_pair_weights(dim: int):
    """`pair_weights` in `dim` = 2 or 3 dimensions (one source, `dims.py`).

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `pair_weights`.
    """

    @nb.njit(cache=True)
    def pair_weights(n_pairs: int, pairs: np.ndarray, pair_g: np.ndarray, x: np.ndarray,
                     perm: np.ndarray, rho: np.ndarray, k_scale: float, rho_scale: float,
                     out: np.ndarray) -> None:
        """The pair weights out[k] = 2F_ab (k_scale kbar_ab + rho_scale / rhobar_ab) of
        the recorded pairs k = (a, b), with 2F_ab = 2 r_ba . grad_a W_ab / |r_ba|^2 (> 0)
        and kbar, rhobar arithmetic means.

        Parameters
        ----------
        n_pairs : int
            number of recorded pairs.
        pairs : (>= n_pairs, 2) int64 array
            the pairs (a, b) of `interactions.pair_sums`.
        pair_g : (>= n_pairs, dim) float64 array
            grad_a W_ab of each pair (1/m^(dim+1)).
        x : (n, dim) float64 array
            positions (m).
        perm : (n,) float64 array
            hydraulic conductivity k (m/s).
        rho : (n,) float64 array
            mixture density (kg/m^3).
        k_scale : float
            factor of the Darcy part: 1 / (m0 gamma_l) (m^3/N) for Eq. (29), m0 of
            `lattice_moment`.
        rho_scale : float
            factor of the velocity-correction part: dt / m0 (s); 0 without it.
        out : (>= n_pairs,) float64 array
            receives the weights.
        """
        for k in range(n_pairs):
            a = pairs[k, 0]
            b = pairs[k, 1]
            dx0 = x[b, 0] - x[a, 0]
            dx1 = x[b, 1] - x[a, 1]
            if dim == 2:
                f2 = 2.0 * (pair_g[k, 0] * dx0 + pair_g[k, 1] * dx1) / (dx0 * dx0 + dx1 * dx1)
            else:
                dx2 = x[b, 2] - x[a, 2]
                f2 = 2.0 * (pair_g[k, 0] * dx0 + pair_g[k, 1] * dx1 + pair_g[k, 2] * dx2) / (
                    dx0 * dx0 + dx1 * dx1 + dx2 * dx2)
            out[k] = f2 * (k_scale * 0.5 * (perm[a] + perm[b])
                           + rho_scale * 2.0 / (rho[a] + rho[b]))

    return pair_weights


pair_weights = make_pair_weights(2)
pair_weights_3d = make_pair_weights(3)


@nb.njit(cache=True)
def operator_coefficients(n_owned: int, n_pairs: int, pairs: np.ndarray, w_diag: np.ndarray,
                          w_off: np.ndarray, vol: np.ndarray, storage: np.ndarray,
                          c_diag: np.ndarray, c_off: np.ndarray, c_storage: np.ndarray,
                          diag: np.ndarray) -> None:
    """The products of `apply_operator` that do not change during a solve, computed once
    per solve for `apply_scaled` (the same roundings, so the same bits), and in the same
    pass the diagonal of S (`operator_diagonal`, the Jacobi preconditioner).

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    n_pairs : int
        number of recorded pairs.
    pairs : (>= n_pairs, 2) int64 array
        the recorded pairs (a, b).
    w_diag, w_off : (>= n_pairs,) float64 arrays
        the pairs' diagonal and off-diagonal weights (`pair_weights`,
        `images.image_weights`).
    vol : (n,) float64 array
        particle volumes (m^3; m^2 per unit thickness in 2D).
    storage : (n,) float64 array
        storage s_i, n / (K_l dt) for the pressure (1/(Pa s)).
    c_diag, c_off : (>= n_pairs,) float64 arrays
        receive V_a V_b w_diag[k] and V_a V_b w_off[k].
    c_storage : (>= n_owned,) float64 array
        receives V_i s_i.
    diag : (>= n_owned,) float64 array
        receives the diagonal of S.
    """
    for i in range(n_owned):
        c_storage[i] = vol[i] * storage[i]
        diag[i] = c_storage[i]
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        vv = vol[a] * vol[b]
        cd = vv * w_diag[k]
        c_diag[k] = cd
        c_off[k] = vv * w_off[k]
        if a < n_owned:
            diag[a] += cd
        if b < n_owned:
            diag[b] += cd


@nb.njit(cache=True)
def apply_scaled(n_owned: int, n_pairs: int, pairs: np.ndarray, c_diag: np.ndarray,
                 c_off: np.ndarray, c_storage: np.ndarray, fixed: np.ndarray, q: np.ndarray,
                 out: np.ndarray) -> None:
    """out[:n_owned] = S q from the coefficients of `operator_coefficients` (the operator
    of `apply_operator`; the solve applies it every iteration).

    Parameters
    ----------
    n_owned, n_pairs, pairs
        as `operator_coefficients`.
    c_diag, c_off, c_storage : float64 arrays
        the coefficients of `operator_coefficients`.
    fixed : (n,) bool array
        rows whose value is imposed.
    q : (n,) float64 array
        the operand (Pa), halo rows included.
    out : (>= n_owned,) float64 array
        receives S q.
    """
    for i in range(n_owned):
        out[i] = c_storage[i] * q[i]
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        wd = c_diag[k]
        wo = c_off[k]
        fa = fixed[a]
        fb = fixed[b]
        qa = 0.0 if fa else q[a]
        qb = 0.0 if fb else q[b]
        if a < n_owned:
            out[a] += wd * q[a] if fa else wd * qa - wo * qb
        if b < n_owned:
            out[b] += wd * q[b] if fb else wd * qb - wo * qa


@nb.njit(cache=True)
def apply_operator(n_owned: int, n_pairs: int, pairs: np.ndarray, w_diag: np.ndarray,
                   w_off: np.ndarray, vol: np.ndarray, storage: np.ndarray, fixed: np.ndarray,
                   q: np.ndarray, out: np.ndarray) -> None:
    """out[:n_owned] = S q (module docstring), a pair k adding V_a V_b (w_diag q_a - w_off q_b)
    to row a (w_diag = w_off = w but where a drained plane's images enter, `images.py`).
    The row of a `fixed` particle is its own diagonal times q_i (scaled like a free row, so
    that one residual norm serves both); a free row keeps the diagonal part of a fixed
    neighbour j, and its coupling to q_j is moved to the right-hand side (`fixed_rhs`), so
    S stays symmetric.

    Parameters
    ----------
    n_owned, n_pairs, pairs, w_diag, w_off, vol, storage
        as `operator_coefficients`.
    fixed : (n,) bool array
        rows whose value is imposed.
    q : (n,) float64 array
        the operand (Pa), halo rows included.
    out : (>= n_owned,) float64 array
        receives S q.
    """
    c_diag = np.empty(n_pairs)
    c_off = np.empty(n_pairs)
    c_storage = np.empty(n_owned)
    operator_coefficients(n_owned, n_pairs, pairs, w_diag, w_off, vol, storage, c_diag,
                          c_off, c_storage, np.empty(n_owned))
    apply_scaled(n_owned, n_pairs, pairs, c_diag, c_off, c_storage, fixed, q, out)


@nb.njit(cache=True)
def operator_diagonal(n_owned: int, n_pairs: int, pairs: np.ndarray, w_diag: np.ndarray,
                      vol: np.ndarray, storage: np.ndarray, out: np.ndarray) -> None:
    """The diagonal of S, V_i s_i + sum_j V_i V_j w_diag_ij, for free and fixed rows alike
    (the Jacobi preconditioner).

    Parameters
    ----------
    n_owned, n_pairs, pairs, w_diag, vol, storage
        as `operator_coefficients`.
    out : (>= n_owned,) float64 array
        receives the diagonal.
    """
    for i in range(n_owned):
        out[i] = vol[i] * storage[i]
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        w = vol[a] * vol[b] * w_diag[k]
        if a < n_owned:
            out[a] += w
        if b < n_owned:
            out[b] += w


@nb.njit(cache=True)
def fixed_rhs(n_owned: int, n_pairs: int, pairs: np.ndarray, w_diag: np.ndarray,
              w_off: np.ndarray, vol: np.ndarray, storage: np.ndarray, fixed: np.ndarray,
              value: np.ndarray, rhs: np.ndarray) -> None:
    """Right-hand side of the imposed values: a fixed row gets its diagonal times its
    value, a free row the couplings w_off_ij value_j of its fixed neighbours.

    Parameters
    ----------
    n_owned, n_pairs, pairs, w_diag, w_off, vol, storage
        as `operator_coefficients`.
    fixed : (n,) bool array
        rows whose value is imposed.
    value : (n,) float64 array
        the imposed values (Pa), read on fixed rows.
    rhs : (>= n_owned,) float64 array
        the right-hand side, added to (fixed rows: set).
    """
    for i in range(n_owned):
        if fixed[i]:
            rhs[i] = vol[i] * storage[i] * value[i]
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        vv = vol[a] * vol[b]
        wd = vv * w_diag[k]
        wo = vv * w_off[k]
        if a < n_owned and fixed[a]:
            rhs[a] += wd * value[a]
        elif a < n_owned and fixed[b]:
            rhs[a] += wo * value[b]
        if b < n_owned and fixed[b]:
            rhs[b] += wd * value[b]
        elif b < n_owned and fixed[a]:
            rhs[b] += wo * value[a]


@nb.njit(cache=True, error_model="numpy")  # x / 0 -> inf as numpy, not an exception
def jacobi(n: int, r: np.ndarray, diag: np.ndarray, u: np.ndarray) -> None:
    """u = r / diag on the first n rows: the Jacobi preconditioner.

    Parameters
    ----------
    n : int
        number of rows.
    r : (>= n,) float64 array
        residual.
    diag : (>= n,) float64 array
        the diagonal of S (`operator_diagonal`).
    u : (>= n,) float64 array
        receives the preconditioned residual.
    """
    for i in range(n):
        u[i] = r[i] / diag[i]


@nb.njit(cache=True, error_model="numpy")  # r / 0 -> inf as in `jacobi`
def cg_advance(n: int, alpha: float, beta: float, u: np.ndarray, w: np.ndarray,
               d: np.ndarray, sd: np.ndarray, x: np.ndarray, r: np.ndarray,
               diag: np.ndarray) -> None:
    """One CG iteration's vector work on the first n rows, in one pass: the search
    direction and, by linearity, its image S d (d = u + beta d, sd = w + beta sd with
    w = S u, so an iteration applies S once, to u; d = u and sd = w when beta = 0,
    whatever d and sd held), the step (x += alpha d, r -= alpha sd), then the Jacobi
    preconditioner (u = r / diag). One call instead of three, the same bits (a CG
    iteration on several ranks is latency-bound).

    Parameters
    ----------
    n : int
        number of rows.
    alpha, beta : float
        the CG step length and direction update (beta = 0: the first iteration).
    u : (>= n,) float64 array
        preconditioned residual; overwritten with the new one.
    w : (>= n,) float64 array
        S u.
    d, sd : (>= n,) float64 arrays
        search direction and S d, updated.
    x : (>= n,) float64 array
        the iterate (Pa), updated.
    r : (>= n,) float64 array
        residual, updated.
    diag : (>= n,) float64 array
        the diagonal of S.
    """
    first = beta == 0.0
    for i in range(n):
        if first:
            di = u[i]
            sdi = w[i]
        else:
            di = u[i] + beta * d[i]
            sdi = w[i] + beta * sd[i]
        d[i] = di
        sd[i] = sdi
        x[i] += alpha * di
        ri = r[i] - alpha * sdi
        r[i] = ri
        u[i] = ri / diag[i]

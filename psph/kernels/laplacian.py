"""Matrix-free SPH Laplacian over the pairs recorded by `pair_sums`, for a pressure solve
(issue 14).

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

import numba as nb
import numpy as np


@nb.njit(cache=True)
def pair_weights(n_pairs: int, pairs: np.ndarray, pair_g: np.ndarray, x: np.ndarray,
                 perm: np.ndarray, rho: np.ndarray, k_scale: float, rho_scale: float,
                 out: np.ndarray) -> None:
    """out[k] = 2F_ab (k_scale kbar_ab + rho_scale / rhobar_ab) for recorded pair k = (a, b),
    with 2F_ab = 2 r_ba . grad_a W_ab / |r_ba|^2 (> 0), kbar, rhobar arithmetic means."""
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        dx0 = x[b, 0] - x[a, 0]
        dx1 = x[b, 1] - x[a, 1]
        f2 = 2.0 * (pair_g[k, 0] * dx0 + pair_g[k, 1] * dx1) / (dx0 * dx0 + dx1 * dx1)
        out[k] = f2 * (k_scale * 0.5 * (perm[a] + perm[b])
                       + rho_scale * 2.0 / (rho[a] + rho[b]))


@nb.njit(cache=True)
def apply_operator(n_owned: int, n_pairs: int, pairs: np.ndarray, weights: np.ndarray,
                   vol: np.ndarray, storage: np.ndarray, fixed: np.ndarray, q: np.ndarray,
                   out: np.ndarray) -> None:
    """out[:n_owned] = S q (module docstring). The row of a `fixed` particle is its own
    diagonal times q_i (scaled like a free row, so that one residual norm serves both); a
    free row keeps the diagonal part w_ij q_i of a fixed neighbour j, and its w_ij q_j is
    moved to the right-hand side (`fixed_rhs`), so S stays symmetric."""
    for i in range(n_owned):
        out[i] = vol[i] * storage[i] * q[i]
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        w = vol[a] * vol[b] * weights[k]
        qa = 0.0 if fixed[a] else q[a]
        qb = 0.0 if fixed[b] else q[b]
        if a < n_owned:
            out[a] += w * (q[a] if fixed[a] else qa - qb)
        if b < n_owned:
            out[b] += w * (q[b] if fixed[b] else qb - qa)


@nb.njit(cache=True)
def operator_diagonal(n_owned: int, n_pairs: int, pairs: np.ndarray, weights: np.ndarray,
                      vol: np.ndarray, storage: np.ndarray, out: np.ndarray) -> None:
    """The diagonal of S, V_i s_i + sum_j V_i V_j w_ij, for free and fixed rows alike (the
    Jacobi preconditioner)."""
    for i in range(n_owned):
        out[i] = vol[i] * storage[i]
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        w = vol[a] * vol[b] * weights[k]
        if a < n_owned:
            out[a] += w
        if b < n_owned:
            out[b] += w


@nb.njit(cache=True)
def fixed_rhs(n_owned: int, n_pairs: int, pairs: np.ndarray, weights: np.ndarray,
              vol: np.ndarray, storage: np.ndarray, fixed: np.ndarray, value: np.ndarray,
              rhs: np.ndarray) -> None:
    """Right-hand side of the imposed values: a fixed row gets its diagonal times its
    value, a free row the couplings w_ij value_j of its fixed neighbours."""
    for i in range(n_owned):
        if fixed[i]:
            rhs[i] = vol[i] * storage[i] * value[i]
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        w = vol[a] * vol[b] * weights[k]
        if a < n_owned and fixed[a]:
            rhs[a] += w * value[a]
        elif a < n_owned and fixed[b]:
            rhs[a] += w * value[b]
        if b < n_owned and fixed[b]:
            rhs[b] += w * value[b]
        elif b < n_owned and fixed[a]:
            rhs[b] += w * value[a]


@nb.njit(cache=True)
def cg_step(n: int, alpha: float, d: np.ndarray, sd: np.ndarray, x: np.ndarray,
            r: np.ndarray) -> None:
    """x += alpha d, r -= alpha S d on the first n rows (no temporaries)."""
    for i in range(n):
        x[i] += alpha * d[i]
        r[i] -= alpha * sd[i]


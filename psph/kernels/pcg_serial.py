"""`psph.solver.pcg.pcg` in one compiled function, for a run on one rank (no halo to refresh).

The same operations in the same order: the operator of `laplacian.apply_scaled`, the
wall-ghost refresh of the search direction (sign times its source row), the Jacobi
preconditioner, and inner products that are correctly rounded exact sums (`exact_dot`,
the bits `Slabs.exact_sum` gives on any rank count). So one rank here and two ranks
through `psph.solver.pcg` give the same iterates, iteration counts and solution
(tests/test_mpi.py), while a step of a small column no longer spends 80 % of its time in
the Python loop of the solve (issue 14: 48 us an iteration for 250 particles).
"""

import math

import numba as nb
import numpy as np

from psph.kernels.exact_sum import exact_dot
from psph.kernels.laplacian import apply_scaled, cg_step


@nb.njit(cache=True)
def _refresh_ghosts(n_real: int, n_total: int, src: np.ndarray, sign: np.ndarray,
                    q: np.ndarray) -> None:
    for g in range(n_real, n_total):
        q[g] = sign[g] * q[src[g]]


@nb.njit(cache=True, error_model="numpy")  # x / 0 -> inf as numpy, not an exception
def pcg_serial(n: int, n_total: int, n_pairs: int, pairs: np.ndarray, c_diag: np.ndarray,
               c_off: np.ndarray, c_storage: np.ndarray, fixed: np.ndarray,
               diag: np.ndarray, rhs: np.ndarray, x: np.ndarray, src: np.ndarray,
               sign: np.ndarray, tol: float, maxiter: int, r: np.ndarray, z: np.ndarray,
               d: np.ndarray, sd: np.ndarray, partials: np.ndarray) -> tuple:
    """Solve S x = rhs on rows 0..n-1 (rows n..n_total-1: wall ghosts, x's current on
    entry). c_diag, c_off, c_storage: the operator's coefficients
    (`laplacian.operator_coefficients`). Returns (iterations, residual, converged) as
    `psph.solver.pcg.pcg`."""
    apply_scaled(n, n_pairs, pairs, c_diag, c_off, c_storage, fixed, x, sd)
    for i in range(n):
        r[i] = rhs[i] - sd[i]
    b_norm = math.sqrt(exact_dot(rhs, rhs, n, partials))
    if b_norm == 0.0:
        b_norm = 1.0
    res = math.sqrt(exact_dot(r, r, n, partials)) / b_norm
    if res <= tol:
        return 0, res, True
    for i in range(n):
        z[i] = r[i] / diag[i]
        d[i] = z[i]
    rz = exact_dot(r, z, n, partials)
    for it in range(1, maxiter + 1):
        _refresh_ghosts(n, n_total, src, sign, d)
        apply_scaled(n, n_pairs, pairs, c_diag, c_off, c_storage, fixed, d, sd)
        dsd = exact_dot(d, sd, n, partials)
        if not (dsd > 0.0 and math.isfinite(dsd)):
            return it, (math.nan if not math.isfinite(dsd) else res), False
        alpha = rz / dsd
        cg_step(n, alpha, d, sd, x, r)
        res = math.sqrt(exact_dot(r, r, n, partials)) / b_norm
        if res <= tol:
            return it, res, True
        for i in range(n):
            z[i] = r[i] / diag[i]
        rz_new = exact_dot(r, z, n, partials)
        if rz == 0.0:  # breakdown, as psph.solver.pcg
            return it, res, False
        beta = rz_new / rz
        rz = rz_new
        for i in range(n):
            d[i] *= beta
        for i in range(n):
            d[i] += z[i]
    return maxiter, res, False

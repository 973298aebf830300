"""`psph.solver.pcg.pcg` in one compiled function, for a run on one rank (no halo to refresh).

The same operations in the same order: the operator of `laplacian.apply_scaled`, the
wall-ghost refresh of the preconditioned residual (sign times its source row), the
Jacobi preconditioner, the Chronopoulos-Gear recurrences, and inner products that are
correctly rounded exact sums (`chunked_dot`, the bits `Slabs.exact_sum` gives on any rank
count). So one rank here and two ranks through `psph.solver.pcg` give the same iterates,
iteration counts and solution (tests/test_mpi.py), while a step of a small column no
longer spends 80 % of its time in the Python loop of the solve (48 us an iteration for 250
particles).
"""

import math

import numba as nb
import numpy as np

from psph.kernels.bundles import CGWork, DotWork, GhostSources, ScaledOperator
from psph.kernels.exact_sum import chunked_dot
from psph.kernels.laplacian import apply_scaled, cg_advance, jacobi


@nb.njit(cache=True)
def _refresh_ghosts(n_real: int, n_total: int, src: np.ndarray, sign: np.ndarray,
                    q: np.ndarray) -> None:
    for g in range(n_real, n_total):
        q[g] = sign[g] * q[src[g]]


@nb.njit(cache=True, error_model="numpy")  # x / 0 -> inf as numpy, not an exception
def pcg_serial(n: int, n_total: int, n_pairs: int, op: ScaledOperator, rhs: np.ndarray,
               x: np.ndarray, ghosts: GhostSources, tol: float, maxiter: int, work: CGWork,
               dots: DotWork, r0: np.ndarray) -> tuple:
    """Solve S x = rhs on rows 0..n-1 with the Chronopoulos-Gear recurrences of
    `psph.solver.pcg.pcg`, step for step.

    Parameters
    ----------
    n : int
        the rows solved for (owned).
    n_total : int
        rows n..n_total-1 are wall ghosts, refreshed from their sources.
    n_pairs : int
        the pairs of op.pairs in use.
    op : bundles.ScaledOperator
        the operator S (`laplacian.operator_coefficients`), its imposed rows and the
        Jacobi diagonal.
    rhs : float array
        the right-hand side (the units of S x).
    x : float array
        the solution (Pa for the pressure increment): the initial guess on entry, its
        ghost rows current.
    ghosts : bundles.GhostSources
        each wall ghost's source row and sign.
    tol : float
        the relative residual ||rhs - S x|| / ||rhs|| to reach.
    maxiter : int
        at most this many iterations.
    work : bundles.CGWork
        scratch vectors of at least n_total rows; r holds the last residual on return.
    dots : bundles.DotWork
        scratch of the exact dot products.
    r0 : float array
        receives the first residual when it has at least n rows.

    Returns
    -------
    tuple
        (iterations, relative residual, converged) as `psph.solver.pcg.pcg`.
    """
    pairs, c_diag, c_off, c_storage, fixed, diag = op
    src, sign = ghosts
    r, u, w, d, sd = work
    row, terms, acc, partials = dots
    apply_scaled(n, n_pairs, pairs, c_diag, c_off, c_storage, fixed, x, w)
    for i in range(n):
        r[i] = rhs[i] - w[i]
    if r0.shape[0] >= n:
        for i in range(n):
            r0[i] = r[i]
    jacobi(n, r, diag, u)
    _refresh_ghosts(n, n_total, src, sign, u)
    apply_scaled(n, n_pairs, pairs, c_diag, c_off, c_storage, fixed, u, w)
    b_norm = math.sqrt(chunked_dot(rhs, rhs, n, row, terms, acc, partials))
    if b_norm == 0.0:
        b_norm = 1.0
    res = math.sqrt(chunked_dot(r, r, n, row, terms, acc, partials)) / b_norm
    if res <= tol:
        return 0, res, True
    ru = chunked_dot(r, u, n, row, terms, acc, partials)
    d_sd = chunked_dot(w, u, n, row, terms, acc, partials)
    beta = 0.0
    for it in range(1, maxiter + 1):
        if not (d_sd > 0.0 and math.isfinite(d_sd)):
            return it, (math.nan if not math.isfinite(d_sd) else res), False
        alpha = ru / d_sd
        cg_advance(n, alpha, beta, u, w, d, sd, x, r, diag)
        _refresh_ghosts(n, n_total, src, sign, u)
        apply_scaled(n, n_pairs, pairs, c_diag, c_off, c_storage, fixed, u, w)
        res = math.sqrt(chunked_dot(r, r, n, row, terms, acc, partials)) / b_norm
        ru_new = chunked_dot(r, u, n, row, terms, acc, partials)
        wu = chunked_dot(w, u, n, row, terms, acc, partials)
        if res <= tol:
            return it, res, True
        if ru == 0.0:  # breakdown, as psph.solver.pcg
            return it, res, False
        beta = ru_new / ru
        d_sd = wu - beta * ru_new / alpha
        ru = ru_new
    return maxiter, res, False

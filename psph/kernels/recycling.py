"""The vector work of the pressure solve's recycled initial guess (`psph/solver/
recycling.py`): a basis X of earlier CG corrections and their images S X, kept as
particle fields (columns of (cap, L) arrays, so they move with their particles), combined
and orthogonalised over the owned rows that are not imposed (`free`).

Inner products whose bits must not depend on the partition are `rounded_dots`: each term
rounded to a multiple of 2^-scale_exp chosen from the largest term over all ranks, then
summed as integers (exact, in any order): the same bits on any number of ranks, to a
precision relative to that largest term (Demmel and Nguyen's pre-rounded reproducible
sum; the guess's coefficients need no more)."""

import numba as nb
import numpy as np


@nb.njit(cache=True)
def max_abs_products(n: int, basis: np.ndarray, k: int, r: np.ndarray,
                     free: np.ndarray) -> float:
    """max |basis[i, j] r[i]| over the free owned rows i < n and the columns j < k."""
    m = 0.0
    for i in range(n):
        if free[i]:
            ri = abs(r[i])
            for j in range(k):
                t = abs(basis[i, j]) * ri
                if t > m:
                    m = t
    return m


@nb.njit(cache=True)
def rounded_dots(n: int, basis: np.ndarray, k: int, r: np.ndarray, free: np.ndarray,
                 scale: float, out: np.ndarray) -> None:
    """out[j] = sum over the free owned rows of round(basis[i, j] r[i] scale) (int64),
    j < k: the terms on one grid, so that the ranks' integer sums add exactly."""
    for j in range(k):
        out[j] = 0
    for i in range(n):
        if free[i]:
            ri = r[i]
            for j in range(k):
                out[j] += np.int64(np.rint(basis[i, j] * ri * scale))


@nb.njit(cache=True)
def combine(n: int, basis: np.ndarray, k: int, c: np.ndarray, free: np.ndarray,
            x: np.ndarray) -> None:
    """x[i] += sum_j c[j] basis[i, j] on the free owned rows."""
    for i in range(n):
        if free[i]:
            s = 0.0
            for j in range(k):
                s += c[j] * basis[i, j]
            x[i] += s


@nb.njit(cache=True)
def orthogonalise(n: int, basis: np.ndarray, images: np.ndarray, k: int, h: np.ndarray,
                  free: np.ndarray, e: np.ndarray, se: np.ndarray) -> None:
    """e -= basis h and se -= images h on the free owned rows; the imposed rows of e and
    se are set to 0 (the basis lives on the free rows)."""
    for i in range(n):
        if free[i]:
            a = 0.0
            b = 0.0
            for j in range(k):
                a += h[j] * basis[i, j]
                b += h[j] * images[i, j]
            e[i] -= a
            se[i] -= b
        else:
            e[i] = 0.0
            se[i] = 0.0


@nb.njit(cache=True)
def store_column(n: int, basis: np.ndarray, images: np.ndarray, j: int, e: np.ndarray,
                 se: np.ndarray, s: float) -> None:
    """basis[:n, j] = s e and images[:n, j] = s se."""
    for i in range(n):
        basis[i, j] = s * e[i]
        images[i, j] = s * se[i]

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
    """The largest term of the products `rounded_dots` sums.

    Parameters
    ----------
    n : int
        owned rows 0..n-1.
    basis : (cap, L) float64 array
        the basis X.
    k : int
        columns in use.
    r : (cap,) float64 array
        the vector (Pa).
    free : (cap,) bool array
        rows whose value is not imposed.

    Returns
    -------
    float
        max |basis[i, j] r[i]| over the free rows i < n and the columns j < k.
    """
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
    """Pre-rounded inner products: out[j] = sum over the free owned rows of
    round(basis[i, j] r[i] scale), j < k, the terms on one grid, so that the ranks'
    integer sums add exactly.

    Parameters
    ----------
    n, basis, k, r, free
        as `max_abs_products`.
    scale : float
        2^scale_exp, from the largest term over all ranks.
    out : (>= k,) int64 array
        receives the sums.
    """
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
    """x[i] += sum_j c[j] basis[i, j] on the free owned rows.

    Parameters
    ----------
    n, basis, k, free
        as `max_abs_products`.
    c : (>= k,) float64 array
        the coefficients.
    x : (cap,) float64 array
        the guess (Pa), added to.
    """
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
    se are set to 0 (the basis lives on the free rows).

    Parameters
    ----------
    n, basis, k, free
        as `max_abs_products`.
    images : (cap, L) float64 array
        the images S X.
    h : (>= k,) float64 array
        the projection coefficients.
    e, se : (cap,) float64 arrays
        the new correction and its image, orthogonalised in place.
    """
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
    """basis[:n, j] = s e and images[:n, j] = s se.

    Parameters
    ----------
    n : int
        owned rows 0..n-1.
    basis, images : (cap, L) float64 arrays
        the basis X and its images S X.
    j : int
        the column to store into.
    e, se : (cap,) float64 arrays
        the correction and its image.
    s : float
        the normalising factor.
    """
    for i in range(n):
        basis[i, j] = s * e[i]
        images[i, j] = s * se[i]

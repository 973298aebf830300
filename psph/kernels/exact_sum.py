"""Exact sums of per-particle terms, for reductions that do not depend on the partition.

A floating-point sum depends on the order of its terms, so a dot product over the owned
particles changes with the way they are split over ranks (and a conjugate-gradient solve
with it, iteration counts included). Here each rank accumulates its terms into a
non-overlapping expansion (Shewchuk 1997, "Adaptive precision floating-point arithmetic
and fast robust geometric predicates"; the algorithm of Python's `math.fsum`): a few
doubles whose exact sum is the exact sum of the rank's terms. The ranks' expansions are
then gathered and summed by `math.fsum`, correctly rounded (`Slabs.exact_sum`). The
result is the correctly rounded exact sum of all terms: the same bits on any rank count.

The terms themselves (a_k b_k rounded once) depend only on the particle, not on the
partition, so rounding the products is harmless.
"""

import math

import numba as nb
import numpy as np

# the parts of a non-overlapping expansion hold disjoint bits of the 2098-bit range of
# doubles, so at most 2098 of them (terms spread over 600 decades already need 84; data
# of one field need a handful)
EXPANSION_CAP = 2100


@nb.njit(cache=True, inline="always")
def _grow(partials: np.ndarray, m: int, x: float) -> int:
    """Add x to the expansion partials[:m] (TwoSum of each part, zeros dropped)."""
    i = 0
    for j in range(m):
        y = partials[j]
        if abs(x) < abs(y):
            x, y = y, x
        hi = x + y
        lo = y - (hi - x)
        if lo != 0.0:
            partials[i] = lo
            i += 1
        x = hi
    partials[i] = x
    return i + 1


@nb.njit(cache=True)
def dot_expansion(a: np.ndarray, b: np.ndarray, n: int, partials: np.ndarray) -> int:
    """Expansion of sum_k a[k] b[k] over k < n into `partials` (EXPANSION_CAP,); returns
    its length, or -1 if a term is not finite (partials[0] then holds it)."""
    m = 0
    for k in range(n):
        x = a[k] * b[k]
        if not math.isfinite(x):
            partials[0] = x
            return -1
        m = _grow(partials, m, x)
    return m


@nb.njit(cache=True)
def sum_expansion(a: np.ndarray, n: int, partials: np.ndarray) -> int:
    """Expansion of sum_k a[k] over k < n; as `dot_expansion`."""
    m = 0
    for k in range(n):
        x = a[k]
        if not math.isfinite(x):
            partials[0] = x
            return -1
        m = _grow(partials, m, x)
    return m


def local_parts(partials: np.ndarray, m: int) -> np.ndarray:
    """The expansion as an array to gather (a non-finite term as a single part)."""
    return partials[:1] if m < 0 else partials[:m]


def exact_total(parts: list[np.ndarray]) -> float:
    """Correctly rounded sum of the gathered expansions of all ranks (NaN if a term was
    not finite or the sum overflows)."""
    flat = np.concatenate(parts) if parts else np.zeros(0)
    if not np.all(np.isfinite(flat)):
        return math.nan
    try:
        return math.fsum(flat.tolist())
    except OverflowError:
        return math.nan


@nb.njit(cache=True)
def rounded_sum(partials: np.ndarray, m: int) -> float:
    """The correctly rounded value of the expansion partials[:m] (increasing magnitude,
    non-overlapping, as `_grow` leaves it): the final step of CPython's `math.fsum`, so
    the same bits as `exact_total` of one rank's parts. NaN for a non-finite term (m < 0)
    or an overflow."""
    if m < 0:
        return math.nan
    if m == 0:
        return 0.0
    n = m - 1
    hi = partials[n]
    lo = 0.0
    while n > 0:
        x = hi
        n -= 1
        y = partials[n]
        hi = x + y
        yr = hi - x
        lo = y - yr
        if lo != 0.0:
            break
    if n > 0 and ((lo < 0.0 and partials[n - 1] < 0.0) or (lo > 0.0 and partials[n - 1] > 0.0)):
        y = lo * 2.0
        x = hi + y
        yr = x - hi
        if y == yr:
            hi = x
    return hi if math.isfinite(hi) else math.nan


@nb.njit(cache=True)
def exact_dot(a: np.ndarray, b: np.ndarray, n: int, partials: np.ndarray) -> float:
    """sum_k a[k] b[k] over k < n, correctly rounded (one rank's `Slabs.exact_sum`)."""
    return rounded_sum(partials, dot_expansion(a, b, n, partials))

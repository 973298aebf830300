"""Exact sums of per-particle terms, for reductions that do not depend on the partition.

A floating-point sum depends on the order of its terms, so a dot product over the owned
particles changes with the way they are split over ranks (and a conjugate-gradient solve
with it, iteration counts included). Here each rank accumulates its terms into a
non-overlapping expansion (Shewchuk 1997, "Adaptive precision floating-point arithmetic
and fast robust geometric predicates"; the algorithm of Python's `math.fsum`): a few
doubles whose exact sum is the exact sum of the rank's terms. The ranks' expansions are
then gathered and summed by `math.fsum`, correctly rounded (`Slabs.exact_sum`). The
result is the correctly rounded exact sum of all terms: the same bits on any rank count,
and the same bits whatever exact method built each expansion (a correctly rounded value
is unique), so the chunk accumulators below give the bits of the expansions.

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


# A term's 53-bit integer mantissa M at bit position s (x = M 2^(s - 1074)) is added to
# 32-bit chunks of int64 accumulators (Neal 2015, "Fast exact summation using small and
# large superaccumulators", arXiv:1505.05571): a term costs three integer additions
# instead of a pass over the expansion, and 2^31 terms cannot overflow a chunk. The
# chunks then become a few doubles, summed by `_grow` into the expansion.
_CHUNKS = 67
_MASK = (1 << 32) - 1
# terms at or above 2^_BIG (and non-finite ones) take the expansion directly: the chunk
# sums of huge terms could overflow a double when the chunks are converted back
_BIG = 960


@nb.njit(cache=True)
def _chunks_to_expansion(acc: np.ndarray, partials: np.ndarray, m: int) -> int:
    """Add the exact value of the chunk accumulators to the expansion partials[:m]."""
    for i in range(_CHUNKS - 1):  # carries up: chunks 0.._CHUNKS-2 in [-2^31, 2^31)
        carry = (acc[i] + (np.int64(1) << 31)) >> 32  # (a negative sum stays in its
        acc[i] -= carry << 32  # chunks instead of borrowing from every chunk above)
        acc[i + 1] += carry
    for i in range(_CHUNKS):
        if acc[i] != 0:
            m = _grow(partials, m, math.ldexp(float(acc[i]), 32 * i - 1074))
    return m


_BLOCK = 256  # terms are formed in blocks of this many, then read as their bits
BLOCK = _BLOCK
CHUNKS = _CHUNKS


@nb.njit(cache=True, inline="always")
def _add_to_chunks(acc: np.ndarray, w: np.int64, ex: np.int64, frac: np.int64) -> None:
    """Add the finite, non-zero double of bits w (exponent field ex, fraction frac, below
    2^_BIG) to the chunk accumulators: |x| = mant 2^(s - 1074), s = ex - 1 for a normal
    number, 0 for a subnormal, the 53-bit mant split over the three chunks it spans."""
    mant = frac | (np.int64(1) << 52) if ex > 0 else frac
    s = ex - 1 if ex > 0 else 0
    ci = s >> 5
    sh = s & 31
    lo = (mant & ((np.int64(1) << (32 - sh)) - 1)) << sh
    mid = (mant >> (32 - sh)) & _MASK
    hi = (mant >> 32) >> (32 - sh)
    if w < 0:
        acc[ci] -= lo
        acc[ci + 1] -= mid
        acc[ci + 2] -= hi
    else:
        acc[ci] += lo
        acc[ci + 1] += mid
        acc[ci + 2] += hi


@nb.njit(cache=True)
def _add_block(terms: np.ndarray, count: int, acc: np.ndarray, partials: np.ndarray,
               m: int, zero: np.ndarray) -> int:
    """Add terms[:count] exactly: to the chunk accumulators from their bits (sign, 11-bit
    exponent, 52-bit fraction), to the expansion partials[:m] if |term| >= 2^_BIG. Zero
    terms are summed in IEEE arithmetic into zero[0] (zero[1] counts them). Returns the
    expansion's length, or -1 with partials[0] = the term if a term is not finite."""
    bits = terms.view(np.int64)
    for k in range(count):
        w = bits[k]
        ex = (w >> 52) & 0x7FF
        frac = w & ((np.int64(1) << 52) - 1)
        if ex == 0x7FF:
            partials[0] = terms[k]
            return -1
        if ex == 0 and frac == 0:
            zero[0] = terms[k] if zero[1] == 0.0 else zero[0] + terms[k]
            zero[1] += 1.0
            continue
        if ex >= _BIG + 1023:
            m = _grow(partials, m, terms[k])
            continue
        _add_to_chunks(acc, w, ex, frac)
    return m


@nb.njit(cache=True)
def _finish(acc: np.ndarray, partials: np.ndarray, m: int, zero: np.ndarray) -> int:
    m = _chunks_to_expansion(acc, partials, m)
    if m == 0 and zero[1] > 0.0:  # only zero terms: their IEEE sum (-0.0 if all are -0.0)
        partials[0] = zero[0]
        m = 1
    return m


@nb.njit(cache=True)
def dot_expansion(a: np.ndarray, b: np.ndarray, n: int, partials: np.ndarray) -> int:
    """The non-overlapping expansion of sum_k a[k] b[k] over k < n.

    Parameters
    ----------
    a, b : (>= n,) float64 arrays
        the factors (any units).
    n : int
        number of terms.
    partials : (EXPANSION_CAP,) float64 array
        receives the expansion's parts, in increasing magnitude.

    Returns
    -------
    int
        the expansion's length, or -1 if a term is not finite (partials[0] then holds it).
    """
    acc = np.zeros(_CHUNKS, np.int64)
    terms = np.empty(_BLOCK)
    zero = np.zeros(2)
    m = 0
    for start in range(0, n, _BLOCK):
        count = min(_BLOCK, n - start)
        for k in range(count):
            terms[k] = a[start + k] * b[start + k]
        m = _add_block(terms, count, acc, partials, m, zero)
        if m < 0:
            return -1
    return _finish(acc, partials, m, zero)


@nb.njit(cache=True)
def sum_expansion(a: np.ndarray, n: int, partials: np.ndarray) -> int:
    """The expansion of sum_k a[k] over k < n, as `dot_expansion` (allocates its scratch;
    `sum_expansion_into` for a sum taken every step).

    Parameters
    ----------
    a : (>= n,) float64 array
        the terms.
    n : int
        number of terms.
    partials : (EXPANSION_CAP,) float64 array
        receives the expansion.

    Returns
    -------
    int
        the expansion's length, or -1 for a non-finite term.
    """
    return sum_expansion_into(a, n, partials, np.zeros(_CHUNKS, np.int64), np.empty(_BLOCK),
                              np.zeros(2))


@nb.njit(cache=True)
def sum_expansion_into(a: np.ndarray, n: int, partials: np.ndarray, acc: np.ndarray,
                       terms: np.ndarray, zero: np.ndarray) -> int:
    """`sum_expansion` with its scratch passed in.

    Parameters
    ----------
    a, n, partials
        as `sum_expansion`.
    acc : (CHUNKS,) int64 array
    terms : (BLOCK,) float64 array
    zero : (2,) float64 array
        scratch, overwritten.

    Returns
    -------
    int
        the expansion's length, or -1 for a non-finite term.
    """
    acc[:] = 0
    zero[:] = 0.0
    m = 0
    for start in range(0, n, _BLOCK):
        count = min(_BLOCK, n - start)
        for k in range(count):
            terms[k] = a[start + k]
        m = _add_block(terms, count, acc, partials, m, zero)
        if m < 0:
            return -1
    return _finish(acc, partials, m, zero)


# `dot_chunks` rows: the chunks, then four counts (summed over ranks like the chunks)
CHUNK_ROW = _CHUNKS + 4
SPECIAL, _POS_ZERO, _NEG_ZERO = _CHUNKS, _CHUNKS + 1, _CHUNKS + 2


@nb.njit(cache=True)
def dot_chunks(a: np.ndarray, b: np.ndarray, n: int, row: np.ndarray,
               terms: np.ndarray) -> None:
    """The terms a[k] b[k], k < n, as integers: their chunk accumulators, carried so that
    every chunk but the top one lies in [-2^31, 2^31), and the counts of terms the chunks
    cannot hold (at or above 2^_BIG or not finite), of +0 and of -0 terms.

    Rows of several ranks add exactly (integer sums, any order, 2^31 ranks before a chunk
    could overflow), so `chunks_value` of their sum is the correctly rounded exact sum of
    all terms on any partition: one integer Allreduce instead of a gather of expansions
    (the CG's collectives on several ranks).

    Parameters
    ----------
    a, b : (>= n,) float64 arrays
        the factors.
    n : int
        number of terms.
    row : (CHUNK_ROW,) int64 array
        receives the chunks (row[:CHUNKS]) and the counts (SPECIAL, +0, -0).
    terms : (BLOCK,) float64 array
        scratch.
    """
    row[:] = 0
    bits = terms.view(np.int64)
    for start in range(0, n, _BLOCK):
        count = min(_BLOCK, n - start)
        for k in range(count):
            terms[k] = a[start + k] * b[start + k]
        for k in range(count):
            w = bits[k]
            ex = (w >> 52) & 0x7FF
            frac = w & ((np.int64(1) << 52) - 1)
            if ex == 0x7FF or ex >= _BIG + 1023:
                row[SPECIAL] += 1
                continue
            if ex == 0 and frac == 0:
                if w < 0:
                    row[_NEG_ZERO] += 1
                else:
                    row[_POS_ZERO] += 1
                continue
            _add_to_chunks(row, w, ex, frac)
        if (start // _BLOCK) % 65536 == 65535:  # 2^24 terms: carry long before 2^31
            _carry(row)
    _carry(row)


@nb.njit(cache=True)
def dot_chunk_rows(a: tuple, b: tuple, n: int, rows: np.ndarray, terms: np.ndarray) -> None:
    """`dot_chunks` of each pair (a[j], b[j]) into rows[j], in one call.

    Parameters
    ----------
    a, b : tuples of (>= n,) float64 arrays
        the factors, as many as rows.
    n : int
        number of terms.
    rows : (len(a), CHUNK_ROW) int64 array
        receives one `dot_chunks` row per pair.
    terms : (BLOCK,) float64 array
        scratch.
    """
    for j in range(len(a)):
        dot_chunks(a[j], b[j], n, rows[j], terms)


@nb.njit(cache=True)
def chunk_row_values(rows: np.ndarray, partials: np.ndarray, acc: np.ndarray,
                     out: np.ndarray) -> bool:
    """`chunks_value` of each (summed) row.

    Parameters
    ----------
    rows : (m, CHUNK_ROW) int64 array
        `dot_chunks` rows, summed over the ranks.
    partials : (EXPANSION_CAP,) float64 array
    acc : (CHUNKS,) int64 array
        scratch.
    out : (m,) float64 array
        receives the values.

    Returns
    -------
    bool
        False, with out untouched, if a row counts a term the chunks cannot hold (the
        caller then sums expansions).
    """
    for j in range(rows.shape[0]):
        if rows[j, SPECIAL] > 0:
            return False
    for j in range(rows.shape[0]):
        out[j] = chunks_value(rows[j], partials, acc)
    return True


@nb.njit(cache=True)
def _carry(acc: np.ndarray) -> None:
    for i in range(_CHUNKS - 1):
        carry = (acc[i] + (np.int64(1) << 31)) >> 32
        acc[i] -= carry << 32
        acc[i + 1] += carry


@nb.njit(cache=True)
def chunks_value(row: np.ndarray, partials: np.ndarray, acc: np.ndarray) -> float:
    """The correctly rounded value of a (summed) `dot_chunks` row, as `exact_dot` of all
    the terms gives it. Call only when row[SPECIAL] == 0 (else the caller sums
    expansions).

    Parameters
    ----------
    row : (CHUNK_ROW,) int64 array
        a `dot_chunks` row.
    partials : (EXPANSION_CAP,) float64 array
    acc : (CHUNKS,) int64 array
        scratch.

    Returns
    -------
    float
        the sum; -0.0 when the non-zero terms cancel or are absent and every zero term is
        -0.0.
    """
    acc[:] = row[:_CHUNKS]
    m = _chunks_to_expansion(acc, partials, 0)
    if m == 0:
        return -0.0 if row[_NEG_ZERO] > 0 and row[_POS_ZERO] == 0 else 0.0
    return rounded_sum(partials, m)


def local_parts(partials: np.ndarray, m: int) -> np.ndarray:
    """The expansion as an array to gather.

    Parameters
    ----------
    partials : float64 array
        the expansion of `dot_expansion` or `sum_expansion`.
    m : int
        its length (-1: a non-finite term, kept as a single part).

    Returns
    -------
    float64 array
        a view of partials.
    """
    return partials[:1] if m < 0 else partials[:m]


def exact_total(parts: list[np.ndarray]) -> float:
    """The correctly rounded sum of the gathered expansions of all ranks, by `math.fsum`
    over one Python list (no array copies: a CG solve on several ranks calls this twice
    an iteration).

    Parameters
    ----------
    parts : list of float64 arrays
        each rank's `local_parts`.

    Returns
    -------
    float
        the sum; NaN if a term was not finite or the sum overflows.
    """
    try:
        total = math.fsum([v for p in parts for v in p.tolist()])
    except (OverflowError, ValueError):  # ValueError: inf - inf
        return math.nan
    return total if math.isfinite(total) else math.nan


@nb.njit(cache=True)
def rounded_sum(partials: np.ndarray, m: int) -> float:
    """The correctly rounded value of an expansion: the final step of CPython's
    `math.fsum`, so the same bits as `exact_total` of one rank's parts.

    Parameters
    ----------
    partials : float64 array
        the expansion, increasing magnitude, non-overlapping (as `_grow` leaves it).
    m : int
        its length; < 0 for a non-finite term.

    Returns
    -------
    float
        the sum; NaN for a non-finite term or an overflow.
    """
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
    """sum_k a[k] b[k] over k < n, correctly rounded (one rank's `Slabs.exact_sum`).

    Parameters
    ----------
    a, b : (>= n,) float64 arrays
        the factors.
    n : int
        number of terms.
    partials : (EXPANSION_CAP,) float64 array
        scratch.

    Returns
    -------
    float
        the sum (NaN for a non-finite term).
    """
    return rounded_sum(partials, dot_expansion(a, b, n, partials))


@nb.njit(cache=True)
def chunked_dot(a: np.ndarray, b: np.ndarray, n: int, row: np.ndarray, terms: np.ndarray,
                acc: np.ndarray, partials: np.ndarray) -> float:
    """`exact_dot` (the same bits) through the chunk accumulators of `dot_chunks`, about
    twice as fast; a huge or non-finite term takes `exact_dot` itself.

    Parameters
    ----------
    a, b, n, partials
        as `exact_dot`.
    row, terms, acc
        scratch as `dot_chunks` and `chunks_value`.

    Returns
    -------
    float
        the sum.
    """
    dot_chunks(a, b, n, row, terms)
    if row[SPECIAL] > 0:
        return exact_dot(a, b, n, partials)
    return chunks_value(row, partials, acc)

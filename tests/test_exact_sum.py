"""Exact, partition-independent sums (`psph.kernels.exact_sum`, issue 14): the reduction
that keeps a conjugate-gradient solve bitwise on any rank count."""

import math

import numpy as np
import pytest

from psph.kernels.exact_sum import (
    BLOCK,
    CHUNK_ROW,
    CHUNKS,
    EXPANSION_CAP,
    SPECIAL,
    chunked_dot,
    chunks_value,
    dot_chunks,
    dot_expansion,
    exact_dot,
    exact_total,
    local_parts,
    sum_expansion,
)


def _ill_conditioned(n=4000, seed=5):
    """Terms over 600 decades with heavy cancellation: a naive sum depends on the order."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=n) * 10.0 ** rng.integers(-300, 300, n)
    b = rng.normal(size=n) * 10.0 ** rng.integers(-8, 8, n)
    # cancelling copies, so the true dot product is small against its terms
    a[n // 2:] = -a[: n // 2] * (1 + 1e-12)
    b[n // 2:] = b[: n // 2]
    return a, b


def _split_dot(a, b, cuts):
    parts = []
    for lo, hi in zip(cuts[:-1], cuts[1:], strict=True):
        buf = np.zeros(EXPANSION_CAP)
        parts.append(local_parts(buf, dot_expansion(a[lo:hi], b[lo:hi], hi - lo, buf)).copy())
    return exact_total(parts)


def test_dot_product_is_the_correctly_rounded_exact_sum():
    a, b = _ill_conditioned()
    expect = math.fsum((a * b).tolist())  # fsum is correctly rounded
    assert _split_dot(a, b, [0, len(a)]) == expect
    buf = np.zeros(EXPANSION_CAP)
    m = sum_expansion(a, len(a), buf)
    assert exact_total([local_parts(buf, m)]) == math.fsum(a.tolist())


def test_any_split_and_order_gives_the_same_bits():
    a, b = _ill_conditioned()
    rng = np.random.default_rng(11)
    ref = _split_dot(a, b, [0, len(a)])
    naive = set()
    for _ in range(8):
        perm = rng.permutation(len(a))
        cuts = [0, *sorted(rng.choice(np.arange(1, len(a)), 3, replace=False)), len(a)]
        assert _split_dot(a[perm], b[perm], cuts) == ref
        naive.add(float(np.sum(a[perm] * b[perm])))
    # the plain floating-point sum does change with the order: the test can see it
    assert len(naive) > 1


def test_a_non_finite_term_gives_nan():
    a = np.array([1.0, np.inf, 2.0])
    assert math.isnan(_split_dot(a, np.ones(3), [0, 3]))
    assert math.isnan(_split_dot(np.array([1e308, 1e308]), np.full(2, 10.0), [0, 2]))


@pytest.mark.mpi(min_size=2)
def test_exact_sum_over_ranks_equals_the_serial_sum():
    from mpi4py import MPI

    from psph.decomposition.slabs import Slabs

    comm = MPI.COMM_WORLD
    a, b = _ill_conditioned()
    cuts = np.linspace(0, len(a), comm.size + 1).astype(int)
    lo, hi = cuts[comm.rank], cuts[comm.rank + 1]
    slabs = Slabs(0, np.linspace(0.0, 1.0, comm.size + 1), comm)
    buf = np.zeros(EXPANSION_CAP)
    m = dot_expansion(a[lo:hi], b[lo:hi], hi - lo, buf)
    assert slabs.exact_sum(local_parts(buf, m)) == math.fsum((a * b).tolist())


def test_subnormal_huge_and_zero_terms_are_summed_exactly():
    """Every branch of the chunk accumulators: subnormal terms, terms above 2^960 (taken
    by the expansion directly), signed zeros, and blocks of more than 256 terms."""
    rng = np.random.default_rng(3)
    tiny = rng.normal(size=300) * 5e-324 * rng.integers(1, 2**20, 300)  # subnormal
    huge = rng.normal(size=20) * 2.0 ** 1000
    mid = rng.normal(size=700) * 10.0 ** rng.integers(-30, 30, 700)
    a = np.concatenate([tiny, huge, mid, -huge, [0.0, -0.0]])
    rng.shuffle(a)
    buf = np.zeros(EXPANSION_CAP)
    assert exact_total([local_parts(buf, sum_expansion(a, len(a), buf))]) == \
        math.fsum(a.tolist())
    assert _split_dot(a, np.ones(len(a)), [0, 517, len(a)]) == math.fsum(a.tolist())
    zeros = np.array([-0.0, -0.0])
    m = sum_expansion(zeros, 2, buf)
    assert m == 1 and math.copysign(1.0, buf[0]) == -1.0


def _chunk_dot(a, b, cuts):
    """dot_chunks of each part, the rows summed as integers (what one Allreduce does)."""
    total = np.zeros(CHUNK_ROW, np.int64)
    row = np.zeros(CHUNK_ROW, np.int64)
    for lo, hi in zip(cuts[:-1], cuts[1:], strict=True):
        dot_chunks(a[lo:hi], b[lo:hi], hi - lo, row, np.zeros(BLOCK))
        total += row
    return total


def test_integer_chunks_summed_over_parts_give_the_exact_dot_bits():
    """The reduction on several ranks (`solver/exact_dots.ExactDots`): chunk rows added as
    integers, in any split, give exactly `exact_dot` of all terms (the one-rank solve)."""
    rng = np.random.default_rng(7)
    a = np.concatenate([rng.normal(size=600) * 10.0 ** rng.integers(-300, 280, 600),
                        rng.normal(size=300) * 5e-324 * rng.integers(1, 2**20, 300)])
    b = rng.normal(size=len(a)) * 10.0 ** rng.integers(-8, 8, len(a))
    a[450:600] = -a[:150] * b[:150] / b[450:600] * (1 + 1e-13)  # heavy cancellation
    buf = np.zeros(EXPANSION_CAP)
    ref = exact_dot(a, b, len(a), buf)
    assert ref == math.fsum((a * b).tolist())
    for cuts in ([0, len(a)], [0, 1, 517, len(a)], [0, 300, 301, 302, len(a)]):
        total = _chunk_dot(a, b, cuts)
        assert total[SPECIAL] == 0
        assert chunks_value(total, buf, np.zeros(CHUNKS, np.int64)) == ref


def test_integer_chunks_flag_huge_and_non_finite_terms_and_keep_signed_zeros():
    buf = np.zeros(EXPANSION_CAP)
    for bad in (np.inf, np.nan, 2.0 ** 1000):
        assert _chunk_dot(np.array([1.0, bad]), np.ones(2), [0, 2])[SPECIAL] == 1
    minus = _chunk_dot(np.array([-0.0, -0.0]), np.ones(2), [0, 1, 2])
    assert math.copysign(1.0, chunks_value(minus, buf, np.zeros(CHUNKS, np.int64))) == -1.0
    assert math.copysign(1.0, exact_dot(np.array([-0.0, -0.0]), np.ones(2), 2, buf)) == -1.0
    mixed = _chunk_dot(np.array([-0.0, 0.0, 1.0, -1.0]), np.ones(4), [0, 2, 4])
    assert math.copysign(1.0, chunks_value(mixed, buf, np.zeros(CHUNKS, np.int64))) == 1.0
    empty = _chunk_dot(np.zeros(0), np.zeros(0), [0, 0])
    assert chunks_value(empty, buf, np.zeros(CHUNKS, np.int64)) == 0.0


def test_chunked_dot_is_exact_dot_bit_for_bit():
    """`chunked_dot` (the one-rank CG's inner products) against `exact_dot`: ordinary
    terms through the chunks, huge and non-finite ones through the expansion, signed zeros."""
    rng = np.random.default_rng(11)
    row, terms = np.zeros(CHUNK_ROW, np.int64), np.zeros(BLOCK)
    acc, buf = np.zeros(CHUNKS, np.int64), np.zeros(EXPANSION_CAP)
    a = rng.normal(size=700) * 10.0 ** rng.integers(-200, 200, 700)
    b = rng.normal(size=700)
    cases = [(a, b), (np.array([1e300, 3.0, -1e300]), np.array([1e10, 1.0, 1e10])),
             (np.array([np.inf, 1.0]), np.ones(2)), (np.array([-0.0, -0.0]), np.ones(2)),
             (np.zeros(0), np.zeros(0))]
    for x, y in cases:
        got = chunked_dot(x, y, len(x), row, terms, acc, buf)
        ref = exact_dot(x, y, len(x), buf)
        assert (math.isnan(got) and math.isnan(ref)) or \
            (got == ref and math.copysign(1.0, got) == math.copysign(1.0, ref)), (got, ref)

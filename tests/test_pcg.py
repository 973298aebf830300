"""The matrix-free pressure operator and its conjugate-gradient solve (issue 14).

The operator S = V (s - L) over the recorded pairs of `pair_sums` is checked against the
matrix assembled from it column by column (symmetric, positive definite, imposed rows), the
SPH Laplacian against the sums of the TPI update (sA, sAp of Eq. 38), and `pcg` against a
dense solve of that matrix."""

import math

import numpy as np
import pytest

from psph.kernels.exact_sum import (
    BLOCK,
    CHUNK_ROW,
    CHUNKS,
    EXPANSION_CAP,
    dot_expansion,
    exact_total,
    local_parts,
)
from psph.kernels.laplacian import (
    apply_operator,
    fixed_rhs,
    operator_coefficients,
    operator_diagonal,
    pair_weights,
)
from psph.kernels.sum_columns import SUM_A, SUM_AP
from psph.solver.pcg import PCGWork, pcg
from tests.helpers import jittered_lattice, sums_for


def _cloud(n_side=14, dx=0.1, seed=2):
    x = jittered_lattice(n_side, dx, 0.15, seed)
    n = len(x)
    rng = np.random.default_rng(seed)
    vol = np.full(n, dx * dx) * rng.uniform(0.9, 1.1, n)
    perm = rng.uniform(0.5, 2.0, n) * 1e-4
    rho = rng.uniform(1800.0, 2100.0, n)
    pairs = (np.zeros((40 * n, 2), np.int64), np.zeros((40 * n, 2)))
    sums, n_pairs = sums_for(x, 1.2 * dx, vol, perm=perm, rho=rho, pairs=pairs)
    return x, vol, perm, rho, pairs[0][:n_pairs], pairs[1][:n_pairs], sums


def _dense(n, apply):
    S = np.zeros((n, n))
    e, out = np.zeros(n), np.zeros(n)
    for j in range(n):
        e[:] = 0.0
        e[j] = 1.0
        apply(e, out)
        S[:, j] = out
    return S


def _serial_dot(n):
    buf = np.zeros(EXPANSION_CAP)

    def dots(*pairs):
        return [exact_total([local_parts(buf, dot_expansion(a, b, n, buf))]) for a, b in pairs]
    return dots


def test_laplacian_weights_are_the_tpi_sums():
    """With k_scale = 1, rho_scale = 0: sum_j V_j w_ij = sA and sum_j V_j w_ij q_j = sAp
    (Eq. 38 with alpha = 0), i.e. the same discrete Darcy operator as the TPI update."""
    x, vol, perm, rho, pairs, g, _ = _cloud()
    n = len(x)
    w = np.zeros(len(pairs))
    pair_weights(len(pairs), pairs, g, x, perm, rho, 1.0, 0.0, w)
    q = np.random.default_rng(4).normal(size=n)
    sums = sums_for(x, 1.2 * 0.1, vol, perm=perm, rho=rho, p=q)
    s_a = np.zeros(n)
    s_aq = np.zeros(n)
    for k, (a, b) in enumerate(pairs):
        s_a[a] += vol[b] * w[k]
        s_a[b] += vol[a] * w[k]
        s_aq[a] += vol[b] * w[k] * q[b]
        s_aq[b] += vol[a] * w[k] * q[a]
    assert np.allclose(s_a, sums[:, SUM_A], rtol=1e-12)
    assert np.allclose(s_aq, sums[:, SUM_AP], rtol=1e-12, atol=1e-12 * np.abs(s_aq).max())


@pytest.mark.parametrize("storage", [0.0, 50.0])
def test_operator_is_symmetric_positive_definite_with_imposed_rows(storage):
    x, vol, perm, rho, pairs, g, _ = _cloud()
    n = len(x)
    w = np.zeros(len(pairs))
    pair_weights(len(pairs), pairs, g, x, perm, rho, 1.0 / 9810.0, 1e-4 / 2000.0, w)
    fixed = x[:, 1] > 1.3  # a drained top
    s = np.full(n, storage)
    S = _dense(n, lambda q, out: apply_operator(n, len(pairs), pairs, w, w, vol, s, fixed, q, out))
    assert np.allclose(S, S.T, rtol=0, atol=1e-14 * np.abs(S).max())
    assert np.linalg.eigvalsh(S).min() > 0.0
    diag = np.zeros(n)
    operator_diagonal(n, len(pairs), pairs, w, vol, s, diag)
    assert np.allclose(diag, np.diag(S), rtol=1e-13)
    # an imposed row is diagonal and no free row sees it
    i = np.flatnonzero(fixed)[0]
    assert S[i, i] > 0.0 and np.count_nonzero(S[:, i]) == 1


def test_pcg_solves_the_operator_with_imposed_values():
    """A drained top (p = 2 kPa) and storage: PCG to 1e-12 matches the dense solve of the
    same system (the imposed couplings moved to the right-hand side)."""
    x, vol, perm, rho, pairs, g, _ = _cloud()
    n = len(x)
    w = np.zeros(len(pairs))
    pair_weights(len(pairs), pairs, g, x, perm, rho, 1.0 / 9810.0, 0.0, w)
    fixed = x[:, 1] > 1.3
    s = np.full(n, 1e-8)
    value = np.where(fixed, 2e3, 0.0)
    rhs = vol * np.random.default_rng(9).normal(0.0, 1e-6, n)
    fixed_rhs(n, len(pairs), pairs, w, w, vol, s, fixed, value, rhs)

    def apply(q, out):
        apply_operator(n, len(pairs), pairs, w, w, vol, s, fixed, q, out)

    diag = np.zeros(n)
    operator_diagonal(n, len(pairs), pairs, w, vol, s, diag)
    p = np.zeros(n)
    res = pcg(apply, diag, rhs, p, n, _serial_dot(n), lambda q: None, 1e-12, 2 * n, PCGWork())
    assert res.converged and res.iterations < n, res
    expect = np.linalg.solve(_dense(n, apply), rhs)
    assert np.allclose(p, expect, rtol=0, atol=1e-9 * np.abs(expect).max())
    assert np.allclose(p[fixed], 2e3, rtol=1e-10)
    # the full system: imposed rows plus the free rows with their imposed neighbours
    out = np.zeros(n)
    w_full = w.copy()
    apply_operator(n, len(pairs), pairs, w_full, w_full, vol, s, np.zeros(n, bool), p, out)
    free = ~fixed
    rhs0 = vol * np.random.default_rng(9).normal(0.0, 1e-6, n)
    terms = np.abs(diag * p).max()  # the size of the terms that cancel in a row
    assert np.allclose(out[free], rhs0[free], rtol=0, atol=1e-9 * terms)
    # a warm start from the answer needs no iteration
    again = pcg(apply, diag, rhs, p.copy(), n, _serial_dot(n), lambda q: None, 1e-8, n,
                PCGWork())
    assert again.iterations == 0 and math.isfinite(again.residual)


def test_compiled_serial_pcg_gives_the_same_bits():
    """`kernels/pcg_serial.py` (one rank) against `psph.solver.pcg` with the exact dot products
    of one rank: same iterates, iteration count, residual and solution, to the last bit,
    with imposed rows and images' split weights (w_diag != w_off)."""
    from psph.kernels.bundles import CGWork, DotWork, GhostSources, ScaledOperator
    from psph.kernels.pcg_serial import pcg_serial

    x, vol, perm, rho, pairs, g, _ = _cloud()
    n = len(x)
    w = np.zeros(len(pairs))
    pair_weights(len(pairs), pairs, g, x, perm, rho, 1.0 / 9810.0, 1e-4 / 2000.0, w)
    w_off = w * np.random.default_rng(5).uniform(0.5, 1.0, len(w))
    fixed = x[:, 1] > 1.3
    s = np.full(n, 1e-6)
    value = np.where(fixed, 2e3, 0.0)
    rhs = vol * np.random.default_rng(9).normal(0.0, 1e-6, n)
    fixed_rhs(n, len(pairs), pairs, w, w_off, vol, s, fixed, value, rhs)
    diag = np.zeros(n)
    operator_diagonal(n, len(pairs), pairs, w, vol, s, diag)

    def apply(q, out):
        apply_operator(n, len(pairs), pairs, w, w_off, vol, s, fixed, q, out)

    p_py = np.where(fixed, value, 0.0)
    res = pcg(apply, diag, rhs, p_py, n, _serial_dot(n), lambda q: None, 1e-10, 2 * n,
              PCGWork())
    p_nb = np.where(fixed, value, 0.0)
    wk = PCGWork()
    wk.ensure(n)
    c_diag, c_off, c_storage = np.zeros(len(pairs)), np.zeros(len(pairs)), np.zeros(n)
    operator_coefficients(n, len(pairs), pairs, w, w_off, vol, s, c_diag, c_off, c_storage,
                          np.zeros(n))
    op = ScaledOperator(pairs, c_diag, c_off, c_storage, fixed, diag)
    dots = DotWork(np.zeros(CHUNK_ROW, np.int64), np.zeros(BLOCK), np.zeros(CHUNKS, np.int64),
                   np.zeros(EXPANSION_CAP))
    it, r, ok = pcg_serial(n, n, len(pairs), op, rhs, p_nb,
                           GhostSources(np.zeros(0, np.int64), np.ones(0)), 1e-10, 2 * n,
                           CGWork(wk.r, wk.u, wk.w, wk.d, wk.sd), dots, np.zeros(0))
    assert res.converged and ok and it == res.iterations and r == res.residual
    assert np.array_equal(p_nb, p_py)


def test_rounded_dots_are_the_same_bits_on_any_split():
    """`kernels/recycling.rounded_dots`: the integer sums of two halves of the rows add to
    those of all rows (the recycled guess's inner products on 1 and 2 ranks), and the
    value is the dot product to the grid's precision."""
    from psph.kernels.recycling import max_abs_products, rounded_dots

    rng = np.random.default_rng(3)
    n, k = 1000, 7
    basis = rng.normal(size=(n, k)) * np.exp(rng.normal(size=(n, 1)) * 3)
    r = rng.normal(size=n)
    free = rng.random(n) > 0.1
    m = max_abs_products(n, basis, k, r, free)
    scale = 2.0 ** (62 - math.frexp(m * n)[1])
    whole, lo, hi = (np.zeros(k, np.int64) for _ in range(3))
    rounded_dots(n, basis, k, r, free, scale, whole)
    rounded_dots(400, basis, k, r, free, scale, lo)
    rounded_dots(n - 400, basis[400:], k, r[400:], free[400:], scale, hi)
    assert np.array_equal(lo + hi, whole)
    exact = (basis[free] * r[free, None]).sum(axis=0)
    assert np.allclose(whole / scale, exact, rtol=0, atol=n * m * 2.0 ** -52)

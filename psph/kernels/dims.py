"""Writing a kernel once for 2D and 3D (issue 37).

A kernel is a factory `make_<kernel>(dim)` whose compiled function closes over `dim` and
the column starts of `sum_columns.sum_layout(dim)`: numba sees them as constants, so the
loops `for m in range(dim)` unroll and the 2D specialisation is the hand-written 2D code
(the same operations in the same order: the same bits). Two rules keep it as fast
(measured, `bench/diagnostics/generic_dim_kernel.py`, docs/developer.md):

* load a pair's components into scalars (`x2 = ... if dim == 3 else 0.0`) before the
  first store into `sums`: a store may alias any float64 array, so a load after it is
  repeated, and the loop over components then costs 30 % more in 2D;
* read a component of those scalars with `pick(m, x0, x1, x2)`, which folds to one of
  them once the loop over m is unrolled.

Written so, the 2D velocity sweep ran in 1.52 ms against the hand-written 1.55 ms (182,099
pairs); with `dim = x.shape[1]` read at run time it took 4.8 ms. A factory's functions are
cached like module-level ones (numba keys the cache by the closure's values).
"""

import numba as nb


@nb.njit(cache=True, inline="always")
def pick(m: int, x0: float, x1: float, x2: float) -> float:
    """x_m of the scalars (x0, x1, x2), for a loop index m that the compiler unrolls."""
    if m == 0:
        return x0
    if m == 1:
        return x1
    return x2


@nb.njit(cache=True, inline="always")
def add_outer(sums, i, c, dim, w, x0, x1, x2, g0, g1, g2):
    """sums[i, c + m dim + q] += w x_m g_q for m, q < dim: a pair's share of a tensor sum
    (M, GV, GS, GN, GA of `sum_columns.py`), in the 2D kernels' order of operations,
    (w x_m) g_q."""
    for m in range(dim):
        xm = pick(m, x0, x1, x2)
        for q in range(dim):
            sums[i, c + m * dim + q] += w * xm * pick(q, g0, g1, g2)


@nb.njit(cache=True, inline="always")
def add_moment(sums, i, c, dim, w, x0, x1, x2, g0, g1, g2):
    """A pair's share of the moment matrix M = sum_j V_j x_ij (x) grad W_ij of Eq. (22):
    `add_outer` in 2D (its bits); in 3D only the upper triangle, as grad W_ij is parallel
    to x_ij and M is symmetric (`mirror_moment` fills the rest after the sweep)."""
    if dim == 2:
        add_outer(sums, i, c, dim, w, x0, x1, x2, g0, g1, g2)
    else:
        w0 = w * x0
        w1 = w * x1
        sums[i, c] += w0 * g0
        sums[i, c + 1] += w0 * g1
        sums[i, c + 2] += w0 * g2
        sums[i, c + 4] += w1 * g1
        sums[i, c + 5] += w1 * g2
        sums[i, c + 8] += w * x2 * g2


@nb.njit(cache=True)
def mirror_moment(sums, n, c):
    """The lower triangle of the 3x3 moment matrices in sums[:n, c:c + 9] from the upper
    (`add_moment`)."""
    for i in range(n):
        sums[i, c + 3] = sums[i, c + 1]
        sums[i, c + 6] = sums[i, c + 2]
        sums[i, c + 7] = sums[i, c + 5]


@nb.njit(cache=True, inline="always")
def velocity_differences(v, v_slip, a, b, va0, va1, va2, ghost_pair, dim):
    """(dv0, dv1, dv2, ds0, ds1, ds2): v_b - v_a (v_a = (va0, va1, va2), loaded by the
    caller, which may hold it for all of a's pairs), and the free-slip v_slip_b - v_slip_a
    on a pair with a wall ghost (else dv); the third components 0 in 2D."""
    dv0 = v[b, 0] - va0
    dv1 = v[b, 1] - va1
    dv2 = v[b, 2] - va2 if dim == 3 else 0.0
    ds0 = dv0
    ds1 = dv1
    ds2 = dv2
    if ghost_pair:
        ds0 = v_slip[b, 0] - v_slip[a, 0]
        ds1 = v_slip[b, 1] - v_slip[a, 1]
        ds2 = v_slip[b, 2] - v_slip[a, 2] if dim == 3 else 0.0
    return dv0, dv1, dv2, ds0, ds1, ds2

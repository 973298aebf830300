"""Writing a kernel once for 2D and 3D.

A kernel is a factory `make_<kernel>(dim)` whose compiled function closes over `dim` and
the column starts of `sum_columns.sum_layout(dim)`: numba sees them as constants, so the
loops `for m in range(dim)` unroll and the 2D specialisation performs the plane-strain
operations in the same order as a kernel written for 2D alone (the same bits). Two rules
keep it as fast (docs/developer.md):

* load a pair's components into scalars (`x2 = ... if dim == 3 else 0.0`) before the
  first store into `sums`: a store may alias any float64 array, so a load after it is
  repeated, and the loop over components then costs 30 % more in 2D;
* read a component of those scalars with `pick(m, x0, x1, x2)`, which folds to one of
  them once the loop over m is unrolled.

Reading `dim = x.shape[1]` at run time instead makes the 2D velocity sweep three times
slower. A factory's functions are cached like module-level ones (numba keys the cache by
the closure's values).
"""

import numba as nb


@nb.njit(cache=True, inline="always")
def pick(m: int, x0: float, x1: float, x2: float) -> float:
    """x_m of the scalars (x0, x1, x2), for a loop index m that the compiler unrolls.

    Parameters
    ----------
    m : int
        component, 0, 1 or 2.
    x0, x1, x2 : float
        the components (any unit).

    Returns
    -------
    float
        x0, x1 or x2.
    """
    if m == 0:
        return x0
    if m == 1:
        return x1
    return x2


@nb.njit(cache=True, inline="always")
def add_outer(sums, i, c, dim, w, x0, x1, x2, g0, g1, g2):
    """sums[i, c + m dim + q] += (w x_m) g_q for m, q < dim: a pair's share of a tensor sum
    (M, GV, GS, GN, GA of `sum_columns.py`).

    Parameters
    ----------
    sums : (cap, nsums) float64 array
        the pair sums, one row per particle.
    i : int
        row to add to.
    c : int
        first column of the dim x dim group (row-major).
    dim : int
        2 or 3.
    w : float
        weight, a neighbour's volume V_j (m^3) times an optional factor.
    x0, x1, x2 : float
        the vector x (m for M, m/s for velocity sums); x2 unused in 2D.
    g0, g1, g2 : float
        the kernel gradient grad_i W_ij (1/m^(dim+1)); g2 unused in 2D.
    """
    for m in range(dim):
        xm = pick(m, x0, x1, x2)
        for q in range(dim):
            sums[i, c + m * dim + q] += w * xm * pick(q, g0, g1, g2)


@nb.njit(cache=True, inline="always")
def add_moment(sums, i, c, dim, w, x0, x1, x2, g0, g1, g2):
    """A pair's share of the moment matrix M = sum_j V_j x_ij (x) grad W_ij of Eq. (22):
    `add_outer` in 2D; in 3D only the upper triangle, as grad W_ij is parallel to x_ij and
    M is symmetric (`mirror_moment` fills the rest after the sweep).

    Parameters
    ----------
    sums, i, c, dim, w, g0, g1, g2
        as `add_outer`.
    x0, x1, x2 : float
        x_ij = x_j - x_i (m).
    """
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
    """The lower triangle of the 3x3 moment matrices from the upper (`add_moment`).

    Parameters
    ----------
    sums : (cap, nsums) float64 array
        the pair sums; rows 0..n-1, columns c..c+8 (row-major M) are completed.
    n : int
        number of rows.
    c : int
        first column of M.
    """
    for i in range(n):
        sums[i, c + 3] = sums[i, c + 1]
        sums[i, c + 6] = sums[i, c + 2]
        sums[i, c + 7] = sums[i, c + 5]


@nb.njit(cache=True, inline="always")
def velocity_differences(v, v_slip, a, b, va0, va1, va2, ghost_pair, dim):
    """A pair's velocity differences, plain and free-slip.

    Parameters
    ----------
    v, v_slip : (cap, dim) float64 arrays
        velocities (m/s); v_slip holds a wall ghost's velocity mirrored as on a free-slip
        wall (`interactions.py`).
    a, b : int
        the pair's rows.
    va0, va1, va2 : float
        v_a (m/s), loaded by the caller, which may hold it for all of a's pairs.
    ghost_pair : bool
        a or b is a wall ghost.
    dim : int
        2 or 3.

    Returns
    -------
    dv0, dv1, dv2, ds0, ds1, ds2 : float
        v_b - v_a and, on a ghost pair, v_slip_b - v_slip_a (else ds = dv) (m/s); the
        third components 0 in 2D.
    """
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

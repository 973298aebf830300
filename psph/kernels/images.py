"""Drained sides at the true surface: antisymmetric pressure images.

A drained side holds p = 0 on its surface, the plane x[axis] = pos, not on the outer
particle layer dx/2 inside it. The Darcy terms of Eq. (23) (the sums Q, sA, sAp and sApsi
of `interactions.py`) see, across the plane, the odd extension of the pore pressure: the
image b* of every neighbour b (its position mirrored, p_b* = -p_b), and each particle's own
image a*. The odd extension of a field that is linear near the plane is the same linear
field, so the SPH Laplacian keeps its exactness there and p = 0 falls on the plane itself.

No image rows are made. Both rows of an image pair lie on the soil side of the plane, and
mirroring one of them only lengthens the pair: |x_a - x_b*| >= |x_a - x_b|. So every image
pair within the 2h support is also a direct pair, and one pass over the pairs the sweep
recorded (same order, so as partition-independent as the sweep) finds them all.
An image pair has both rows within 2h of the plane (|x_a - x_b*| >= d_a + d_b, their
distances to it), so the pass skips a pair whose row a is farther (`_within_reach`). The
sweep records a row's pairs one after another, so that test is made once a row, and the
pairs far from the plane (most of them) cost a read of their row a only (without the
test the pass takes a sixth of a 3D step).

A plane row of `planes` is (axis, pos, sign, active): sign +1 with the soil at larger
x[axis]. Walls with mirror ghosts get the same extension from their ghosts instead (p of a
drained wall's ghost is -p of its source, `ghosts.py`); planes are for the free sides.
"""

import math

import numba as nb
import numpy as np

from psph.kernels.bundles import ImageFields, ImageWeights, PairFields, PairParams
from psph.kernels.spline import dw_cubic_dim
from psph.kernels.sum_columns import Q_X, SUM_A, SUM_AP, SUM_APSI, sum_layout

# the Darcy columns: Q (dim), then SUM_A, SUM_AP, SUM_APSI in a row, in 2D and 3D
Q3, SUM_A3 = sum_layout(3).Q, sum_layout(3).SUM_A
assert SUM_AP == SUM_A + 1 and SUM_APSI == SUM_A + 2 and sum_layout(3).SUM_APSI == SUM_A3 + 2


@nb.njit(cache=True, inline="always")
def _add_image(sums, i, vol_j, kbar, f2, p_image, d, par, three):
    """One image neighbour at x_i + d, d = (d0, d1, d2) (d2 unused in 2D), with pressure
    p_image into row i of sums (indexed in place: a row view per pair costs more than the
    pair's arithmetic); par.rho_l_b0, rho_l_b1, rho_l_b2: rho_l times the body force
    (`bundles.PairParams`); three: the 3D layout of sums."""
    d0, d1, d2 = d
    b0, b1, b2 = par.rho_l_b0, par.rho_l_b1, par.rho_l_b2
    aij = vol_j * kbar * f2
    if three:
        cq, ca = Q3, SUM_A3
        sums[i, cq + 2] += vol_j * d2 * f2
    else:
        cq, ca = Q_X, SUM_A
    sums[i, cq] += vol_j * d0 * f2
    sums[i, cq + 1] += vol_j * d1 * f2
    sums[i, ca] += aij
    sums[i, ca + 1] += aij * p_image  # SUM_AP
    head = b0 * d0 + b1 * d1
    if three:
        head += b2 * d2
    sums[i, ca + 2] += aij * -head  # SUM_APSI


@nb.njit(cache=True, inline="always")
def _plane(planes, q):
    """(axis, position, sign) of plane q, axis -1 while it is inactive."""
    if planes[q, 3] == 0.0:
        return -1, 0.0, 0.0
    return int(planes[q, 0]), planes[q, 1], planes[q, 2]


@nb.njit(cache=True, inline="always")
def _reach(h, pos):
    """How far from the plane x[axis] = pos a row of an image pair can be: 2h, with a
    margin above the rounding of `_image_of_pair`'s d_ax = 2 pos - x_a - x_b (a few ulps of
    |pos|), so that a row this test turns away is out of that support too."""
    return 2.0 * h * (1.0 + 1e-9) + 1e-14 * abs(pos)


@nb.njit(cache=True, inline="always")
def _within_reach(x, a, ax, pos, sg, reach):
    """Whether row a lies on the plane's soil side within `reach` of it."""
    d = sg * (x[a, ax] - pos)
    return 0.0 < d < reach


@nb.njit(cache=True, inline="always")
def _others(ax):
    """The other two axes of ax (in 2D, where ax is 0 or 1, the first is the other)."""
    return (1 if ax == 0 else 0), (1 if ax == 2 else 2)


@nb.njit(cache=True, inline="always")
def _image_of_pair(x, a, b, ax, pos, sg, support2, three):
    """(d_ax, d_o1, d_o2, r) of b's image seen from a across the plane x[ax] = pos (d_ax
    along the axis, d_o1 and d_o2 across, `_others`; d_o2 = 0 in 2D; the same for a's
    image seen from b, d_o reversed), or r = -1 when a row is beyond the plane or the
    image is out of the 2h support."""
    if sg * (x[a, ax] - pos) <= 0.0 or sg * (x[b, ax] - pos) <= 0.0:
        return 0.0, 0.0, 0.0, -1.0
    o1, o2 = _others(ax)
    d_ax = 2.0 * pos - x[a, ax] - x[b, ax]  # x_b*[ax] - x_a[ax] = x_a*[ax] - x_b[ax]
    d_o1 = x[b, o1] - x[a, o1]
    r2 = d_ax * d_ax + d_o1 * d_o1
    d_o2 = 0.0
    if three:
        d_o2 = x[b, o2] - x[a, o2]
        r2 += d_o2 * d_o2
    if r2 >= support2:
        return 0.0, 0.0, 0.0, -1.0
    return d_ax, d_o1, d_o2, math.sqrt(r2)


@nb.njit(cache=True, inline="always")
def _components(ax, d_ax, d_o1, d_o2):
    """(d0, d1, d2) of a displacement d_ax along ax and (d_o1, d_o2) across (`_others`)."""
    if ax == 0:
        return d_ax, d_o1, d_o2
    if ax == 1:
        return d_o1, d_ax, d_o2
    return d_o1, d_o2, d_ax


def make_image_sums(dim: int):
    """`image_sums` in `dim` = 2 or 3 dimensions (one source, `dims.py`).

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `image_sums`.
    """
    three = dim == 3

    @nb.njit(cache=True, error_model="numpy")
    def image_sums(n_owned: int, n_pairs: int, pairs: np.ndarray, fields: PairFields,
                   planes: np.ndarray, par: PairParams, sums: np.ndarray) -> None:
        """Add the images across each active plane to the Darcy sums (Q, SUM_A, SUM_AP,
        SUM_APSI) of owned rows: the image of the other row of every recorded pair, then
        each row's own image. p~ = p + alpha (p - p_prev) as in Eq. (38)-(39); the
        elevation head psi = -rho_l b.x is taken at the image's position (it is a known
        field, not mirrored).

        Parameters
        ----------
        n_owned : int
            owned rows 0..n_owned-1.
        n_pairs : int
            pairs recorded by `interactions.pair_sums`.
        pairs : (>= n_pairs, 2) int64 array
            the recorded pairs (a, b), in visiting order.
        fields : `bundles.PairFields`
            the fields of the pair sweep; read here: positions x (m), pore pressure now
            and one step before p, p_prev (Pa), volumes vol (m^3; m^2 per unit thickness
            in 2D) and hydraulic conductivity perm (m/s).
        planes : (n_planes, 4) float64 array
            rows (axis, position (m), sign, active): sign +1 with the soil at larger
            x[axis]; active 0 while the side is not yet drained.
        par : `bundles.PairParams`
            the scalars of the pair sweep; read here: the smoothing length h (m), alpha
            of Eq. (39) tpi_alpha (0 for the explicit scheme) and rho_l times the body
            force rho_l_b0, rho_l_b1, rho_l_b2 (N/m^3; rho_l_b2 in 3D only).
        sums : (cap, nsums) float64 array
            the pair sums, `sum_columns.sum_layout(dim)`; the Darcy columns are added to.
        """
        x, p, p_prev, vol, perm = fields.x, fields.p, fields.p_prev, fields.vol, fields.perm
        h, tpi_alpha = par.h, par.tpi_alpha
        support2 = 4.0 * h * h
        for q in range(planes.shape[0]):
            ax, pos, sg = _plane(planes, q)
            if ax < 0:
                continue
            reach = _reach(h, pos)
            last_a = -1
            a_near = False
            for k in range(n_pairs):
                a = pairs[k, 0]
                if a != last_a:
                    last_a = a
                    a_near = _within_reach(x, a, ax, pos, sg, reach)
                if not a_near:
                    continue
                b = pairs[k, 1]
                d_ax, d_o1, d_o2, r = _image_of_pair(x, a, b, ax, pos, sg, support2, three)
                if r < 0.0:
                    continue
                f2 = -2.0 * dw_cubic_dim(r, h, dim) / r
                kbar = 0.5 * (perm[a] + perm[b])
                if a < n_owned:
                    pt = p[b] + tpi_alpha * (p[b] - p_prev[b])
                    _add_image(sums, a, vol[b], kbar, f2, -pt,
                               _components(ax, d_ax, d_o1, d_o2), par, three)
                if b < n_owned:
                    pt = p[a] + tpi_alpha * (p[a] - p_prev[a])
                    _add_image(sums, b, vol[a], kbar, f2, -pt,
                               _components(ax, d_ax, -d_o1, -d_o2), par, three)
            for i in range(n_owned):
                d_ax = 2.0 * (pos - x[i, ax])
                if sg * d_ax >= 0.0 or d_ax * d_ax >= support2:
                    continue
                r = abs(d_ax)
                f2 = -2.0 * dw_cubic_dim(r, h, dim) / r
                pt = p[i] + tpi_alpha * (p[i] - p_prev[i])
                _add_image(sums, i, vol[i], perm[i], f2, -pt, _components(ax, d_ax, 0.0, 0.0),
                           par, three)

    return image_sums


image_sums = make_image_sums(2)
image_sums_3d = make_image_sums(3)


@nb.njit(cache=True)
def image_weights(n_owned: int, n_pairs: int, pairs: np.ndarray, fields: ImageFields,
                  planes: np.ndarray, h: float, k_scale: float, rho_scale: float,
                  w: np.ndarray, out: ImageWeights) -> None:
    """The images in the operator of the pressure solve (`laplacian.py`): a recorded pair
    (a, b) of weight w couples a to b* with the weight w* = 2F_ab* (k_scale kbar +
    rho_scale / rhobar), and q_a - q_b* = q_a + q_b, so the pair's diagonal weight is
    w + w* and its off-diagonal w - w* (still symmetric: the reflection keeps
    |x_a - x_b*| = |x_b - x_a*|). A row's own image adds 2 V_i w*_ii q_i, kept in
    out.storage (V_i storage_i q_i of the operator).

    Planes exist for the free sides that drain with `drained_boundary = "mirror"` (a side
    that stays a plane, `drainage.py`); an impervious or non-planar free surface has no
    image here, and its correction keeps the mismatch below.
    The Darcy part (k_scale) is imaged once the plane's side has drained (planes[q, 3]).
    The velocity-correction part (rho_scale = dt) is imaged from the start: the
    correction takes the pair-symmetric gradient of Eq. (26), whose self term
    -2 dp_i S_i / rho_i is, on a plane surface, the antisymmetric image of the particle's
    own increment. Without that image in the operator the correction changes div v at a
    loaded top by other than the solve counted on, and at twice the solid cap a
    period-2 mode of p grows about 2.8x a step (`tests/test_projection.py`).

    Parameters
    ----------
    n_owned, n_pairs, pairs, planes
        as `image_sums`.
    fields : `bundles.ImageFields`
        positions x (m), hydraulic conductivity perm (m/s), mixture density rho
        (kg/m^3) and volumes vol (m^3; m^2 per unit thickness in 2D).
    h : float
        smoothing length (m).
    k_scale, rho_scale : float
        the factors of the Darcy and velocity-correction parts, as
        `laplacian.pair_weights` (m^3/N and s).
    w : (n_pairs,) float64 array
        the pairs' weights without images (`laplacian.pair_weights`).
    out : `bundles.ImageWeights`
        w_diag, w_off, (n_pairs,) float64 arrays, receive w + w* and w - w*; a row's own
        image is added to storage, (n,) float64 (V_i storage_i q_i of the operator).
    """
    x, perm, rho, vol = fields.x, fields.perm, fields.rho, fields.vol
    w_diag, w_off, storage = out.w_diag, out.w_off, out.storage
    support2 = 4.0 * h * h
    for k in range(n_pairs):
        w_diag[k] = w[k]
        w_off[k] = w[k]
    for q in range(planes.shape[0]):
        ax, pos, sg = int(planes[q, 0]), planes[q, 1], planes[q, 2]
        reach = _reach(h, pos)
        darcy = k_scale if planes[q, 3] != 0.0 else 0.0
        last_a = -1
        a_near = False
        for k in range(n_pairs):
            a = pairs[k, 0]
            if a != last_a:  # a row's pairs follow one another: `image_sums`
                last_a = a
                a_near = _within_reach(x, a, ax, pos, sg, reach)
            if not a_near:
                continue
            b = pairs[k, 1]
            r = _image_of_pair(x, a, b, ax, pos, sg, support2, x.shape[1] == 3)[3]
            if r < 0.0:
                continue
            wi = -2.0 * dw_cubic_dim(r, h, x.shape[1]) / r * (darcy * 0.5 * (perm[a] + perm[b])
                                               + rho_scale * 2.0 / (rho[a] + rho[b]))
            w_diag[k] += wi
            w_off[k] -= wi
        for i in range(n_owned):
            d_ax = 2.0 * (pos - x[i, ax])
            if sg * d_ax >= 0.0 or d_ax * d_ax >= support2:
                continue
            r = abs(d_ax)
            storage[i] += 2.0 * vol[i] * (-2.0 * dw_cubic_dim(r, h, x.shape[1]) / r) * (
                darcy * perm[i] + rho_scale / rho[i])


@nb.njit(cache=True)
def row_displacement(n_owned: int, x: np.ndarray, u: np.ndarray, axis: int, pos: float,
                     sign: float, width: float, out: np.ndarray) -> int:
    """The displacements along `axis` of the outer particle layer of a free drained side.

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    x, u : (n, dim) float64 arrays
        positions and displacements (m).
    axis : int
        the plane's normal axis.
    pos : float
        the plane's position (m).
    sign : float
        +1 with the soil at larger x[axis], else -1.
    width : float
        thickness of the layer (m).
    out : (>= n_owned,) float64 array
        receives u[i, axis] of the rows within `width` on the soil side, in row order.

    Returns
    -------
    int
        the number m of rows written.
    """
    m = 0
    for i in range(n_owned):
        d = sign * (x[i, axis] - pos)
        if 0.0 < d < width:
            out[m] = u[i, axis]
            m += 1
    return m

"""Shepard filter of the pore pressure, Eq. (46), and the stress regularisation.

p_i <- sum_j V_j W_ij p_j / sum_j V_j W_ij over the neighbours j within 2h (i included).
Zeroth-order (constant-preserving) smoothing of the pressure noise; Section 3.5.2 applies
it every m = 20-40 steps. Neighbours include halo rows and wall ghosts (which carry the
mirrored pressure), so a wall behaves as a symmetry plane.
"""

import math

import numba as nb

from psph.kernels.neighbours import half_stencil
from psph.kernels.spline import w_cubic


@nb.njit(cache=True)
def shepard_sums(n_total, n_owned, x, f, vol, cell_start, order, ncell, h, num, den):
    """num[i, c] = sum_j V_j W_ij f[j, c] and den[i] = sum_j V_j W_ij over the neighbours
    j within 2h of owned particle i (i included), the sums of Eq. (46) for every column
    of f; halo rows and wall ghosts are neighbours."""
    w0 = w_cubic(0.0, h)
    m = f.shape[1]
    for i in range(n_owned):
        den[i] = vol[i] * w0
        for c in range(m):
            num[i, c] = vol[i] * w0 * f[i, c]
    ncx = ncell[0]
    ncy = ncell[1]
    support2 = 4.0 * h * h
    for cy in range(ncy):
        for cx in range(ncx):
            c0 = cy * ncx + cx
            for sa in range(cell_start[c0], cell_start[c0 + 1]):
                a = order[sa]
                for k in range(5):
                    nc, s0 = half_stencil(k, c0, sa, cx, cy, ncx, ncy, cell_start)
                    if nc < 0:
                        continue
                    for sb in range(s0, cell_start[nc + 1]):
                        b = order[sb]
                        if a >= n_owned and b >= n_owned:
                            continue
                        d0 = x[b, 0] - x[a, 0]
                        d1 = x[b, 1] - x[a, 1]
                        r2 = d0 * d0 + d1 * d1
                        if r2 >= support2:
                            continue
                        w = w_cubic(math.sqrt(r2), h)
                        if a < n_owned:
                            den[a] += vol[b] * w
                            for c in range(m):
                                num[a, c] += vol[b] * w * f[b, c]
                        if b < n_owned:
                            den[b] += vol[a] * w
                            for c in range(m):
                                num[b, c] += vol[a] * w * f[a, c]


@nb.njit(cache=True)
def shepard_pressure(n_total, n_owned, x, p, p_prev, vol, drained_from, t, cell_start, order,
                     ncell, h, num, den):
    """Filter p of particles 0..n_owned-1 in place (Eq. 46). Particles with an imposed
    pressure (drained_from <= t) keep it. p_prev moves with p, so the TPI increment
    p - p_prev of Eq. (39) is not changed by the filter. num, den: scratch arrays of
    length >= n_owned."""
    num2 = num.reshape((num.shape[0], 1))
    shepard_sums(n_total, n_owned, x, p.reshape((p.shape[0], 1)), vol, cell_start, order,
                 ncell, h, num2, den)
    for i in range(n_owned):
        if drained_from[i] > t and den[i] > 0.0:
            filtered = num[i] / den[i]
            p_prev[i] += filtered - p[i]
            p[i] = filtered


@nb.njit(cache=True)
def shepard_stress(n_total, n_owned, x, stress, vol, cell_start, order, ncell, h, num, den):
    """Filter the effective stress (xx, yy, zz, xy) of particles 0..n_owned-1 in place with
    the same zeroth-order Shepard sum as Eq. (46): the stress regularisation the paper
    points to for this noise (its ref. [14], there with MLS). The odd-even mode of sigma'
    is invisible to the pair-symmetric divergence of Eq. (26), so nothing else damps it.
    Wall ghosts carry the mirrored stress. num: scratch (>= n_owned, 4); den: >= n_owned."""
    shepard_sums(n_total, n_owned, x, stress, vol, cell_start, order, ncell, h, num, den)
    for i in range(n_owned):
        if den[i] > 0.0:
            for c in range(4):
                stress[i, c] = num[i, c] / den[i]


@nb.njit(cache=True)
def mls_stress(n_total, n_owned, x, stress, vol, cell_start, order, ncell, h, moments):
    """Filter the effective stress (xx, yy, zz, xy) of particles 0..n_owned-1 in place with
    the first-order moving-least-squares kernel, the stress regularisation of the paper's
    ref. [14] (Section 3.5.2):

        sigma_i <- sum_j V_j W_ij (beta_i . q_ij) sigma_j,   q_ij = (1, x_j - x_i),
        A_i beta_i = (1, 0, 0),   A_i = sum_j V_j W_ij q_ij q_ij^T   (i included).

    It reproduces linear fields exactly, also where the support is cut: the zeroth-order
    Shepard sum pulls a free-surface particle's stress toward its interior neighbours',
    away from what its own strain carries, while Eq. (24) keeps integrating the strain
    into the porosity (issue 13: n drifted to 0 at the slope face). Where A_i is nearly
    singular (fewer than about three neighbours off a line) it falls back to Shepard.
    moments: scratch (>= n_owned, 18): A (6 entries) and b = sum V W q sigma (3 x 4)."""
    w0 = w_cubic(0.0, h)
    for i in range(n_owned):
        for c in range(18):
            moments[i, c] = 0.0
        moments[i, 0] = vol[i] * w0
        for c in range(4):
            moments[i, 6 + c] = vol[i] * w0 * stress[i, c]
    ncx = ncell[0]
    ncy = ncell[1]
    support2 = 4.0 * h * h
    for cy in range(ncy):
        for cx in range(ncx):
            c0 = cy * ncx + cx
            for sa in range(cell_start[c0], cell_start[c0 + 1]):
                a = order[sa]
                for k in range(5):
                    nc, s0 = half_stencil(k, c0, sa, cx, cy, ncx, ncy, cell_start)
                    if nc < 0:
                        continue
                    for sb in range(s0, cell_start[nc + 1]):
                        b = order[sb]
                        if a >= n_owned and b >= n_owned:
                            continue
                        d0 = x[b, 0] - x[a, 0]
                        d1 = x[b, 1] - x[a, 1]
                        r2 = d0 * d0 + d1 * d1
                        if r2 >= support2:
                            continue
                        w = w_cubic(math.sqrt(r2), h)
                        if a < n_owned:
                            _mls_add(moments[a], vol[b] * w, d0, d1, stress[b])
                        if b < n_owned:
                            _mls_add(moments[b], vol[a] * w, -d0, -d1, stress[a])
    for i in range(n_owned):
        m = moments[i]
        a00, a01, a02, a11, a12, a22 = m[0], m[1], m[2], m[3], m[4], m[5]
        # beta = A^-1 e1: the first column of the inverse (cofactors / det)
        q0 = a11 * a22 - a12 * a12
        q1 = a02 * a12 - a01 * a22
        q2 = a01 * a12 - a02 * a11
        det = a00 * q0 + a01 * q1 + a02 * q2
        # scale-free test: det against the product of the diagonal (1 for a full support)
        if a00 > 0.0 and abs(det) > 1e-6 * a00 * a11 * a22:
            b0, b1, b2 = q0 / det, q1 / det, q2 / det
        elif a00 > 0.0:
            b0, b1, b2 = 1.0 / a00, 0.0, 0.0
        else:
            continue
        for c in range(4):
            stress[i, c] = b0 * m[6 + c] + b1 * m[10 + c] + b2 * m[14 + c]


@nb.njit(cache=True, inline="always")
def _mls_add(m, vw, d0, d1, s):
    """Add neighbour j (weight V_j W_ij, offset x_j - x_i, stress s) to the MLS moments."""
    m[0] += vw
    m[1] += vw * d0
    m[2] += vw * d1
    m[3] += vw * d0 * d0
    m[4] += vw * d0 * d1
    m[5] += vw * d1 * d1
    for c in range(4):
        m[6 + c] += vw * s[c]
        m[10 + c] += vw * d0 * s[c]
        m[14 + c] += vw * d1 * s[c]

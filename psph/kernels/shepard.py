"""Shepard filter of the pore pressure, Eq. (46).

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

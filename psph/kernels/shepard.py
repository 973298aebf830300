"""Shepard filter of the pore pressure, Eq. (46), and the stress regularisation.

p_i <- sum_j V_j W_ij p_j / sum_j V_j W_ij over the neighbours j within 2h (i included).
Zeroth-order (constant-preserving) smoothing of the pressure noise; Section 3.5.2 applies
it every m = 20-40 steps. Neighbours include halo rows and wall ghosts (which carry the
mirrored pressure), so a wall behaves as a symmetry plane. The effective stress can be
regularised in the same step, with the same sum or with its first-order (MLS) form.
All three filters share one pair sweep, `kernel_moments`.
"""

import math

import numba as nb

from psph.kernels.neighbours import half_stencil
from psph.kernels.spline import w_cubic


@nb.njit(cache=True)
def kernel_moments(n_owned, x, f, vol, cell_start, order, ncell, h, first_order, mom):
    """Kernel-weighted moments of the columns of f over the neighbours j within 2h of every
    owned particle i (i included; halo rows and wall ghosts are neighbours), w = V_j W_ij:

    first_order False: mom[i, 0] = sum w, mom[i, 1 + c] = sum w f[j, c] (Eq. 46's sums);
    first_order True, q = (1, x_j - x_i): mom[i, 0:6] = A = sum w q q^T (00, 01, 02, 11,
    12, 22) and mom[i, 6 + 3 c + k] = sum w q_k f[j, c]. mom needs 1 + m resp. 6 + 3 m
    columns for m columns of f."""
    m = f.shape[1]
    w0 = w_cubic(0.0, h)
    width = 6 + 3 * m if first_order else 1 + m
    for i in range(n_owned):
        for c in range(width):
            mom[i, c] = 0.0
        _add_moments(mom[i], vol[i] * w0, 0.0, 0.0, f[i], first_order)
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
                            _add_moments(mom[a], vol[b] * w, d0, d1, f[b], first_order)
                        if b < n_owned:
                            _add_moments(mom[b], vol[a] * w, -d0, -d1, f[a], first_order)


@nb.njit(cache=True, inline="always")
def _add_moments(row, w, d0, d1, fj, first_order):
    """Add neighbour j (weight w = V_j W_ij, offset x_j - x_i, values fj) to one row."""
    m = fj.shape[0]
    if not first_order:
        row[0] += w
        for c in range(m):
            row[1 + c] += w * fj[c]
        return
    row[0] += w
    row[1] += w * d0
    row[2] += w * d1
    row[3] += w * d0 * d0
    row[4] += w * d0 * d1
    row[5] += w * d1 * d1
    for c in range(m):
        row[6 + 3 * c] += w * fj[c]
        row[7 + 3 * c] += w * d0 * fj[c]
        row[8 + 3 * c] += w * d1 * fj[c]


@nb.njit(cache=True)
def shepard_pressure(n_total, n_owned, x, p, p_prev, vol, drained_from, t, cell_start, order,
                     ncell, h, mom):
    """Filter p of particles 0..n_owned-1 in place (Eq. 46). Particles with an imposed
    pressure (drained_from <= t) keep it. p_prev moves with p, so the TPI increment
    p - p_prev of Eq. (39) is not changed by the filter. mom: scratch (>= n_owned, 2)."""
    kernel_moments(n_owned, x, p.reshape((p.shape[0], 1)), vol, cell_start, order, ncell, h,
                   False, mom)
    for i in range(n_owned):
        if drained_from[i] > t and mom[i, 0] > 0.0:
            filtered = mom[i, 1] / mom[i, 0]
            p_prev[i] += filtered - p[i]
            p[i] = filtered


@nb.njit(cache=True)
def shepard_stress(n_total, n_owned, x, stress, vol, cell_start, order, ncell, h, mom):
    """Filter the effective stress (xx, yy, zz, xy) of particles 0..n_owned-1 in place with
    the same zeroth-order Shepard sum as Eq. (46): the stress regularisation the paper
    points to for this noise (its ref. [14], there with MLS, `mls_stress`). The odd-even
    mode of sigma' is invisible to the pair-symmetric divergence of Eq. (26), so nothing
    else damps it. Wall ghosts carry the mirrored stress. mom: scratch (>= n_owned, 5)."""
    kernel_moments(n_owned, x, stress, vol, cell_start, order, ncell, h, False, mom)
    for i in range(n_owned):
        if mom[i, 0] > 0.0:
            for c in range(4):
                stress[i, c] = mom[i, 1 + c] / mom[i, 0]


@nb.njit(cache=True)
def mls_stress(n_total, n_owned, x, stress, vol, cell_start, order, ncell, h, mom):
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
    mom: scratch (>= n_owned, 18)."""
    kernel_moments(n_owned, x, stress, vol, cell_start, order, ncell, h, True, mom)
    for i in range(n_owned):
        r = mom[i]
        a00, a01, a02, a11, a12, a22 = r[0], r[1], r[2], r[3], r[4], r[5]
        # beta = A^-1 e1: the first column of the inverse (cofactors / det)
        q0 = a11 * a22 - a12 * a12
        q1 = a02 * a12 - a01 * a22
        q2 = a01 * a12 - a02 * a11
        det = a00 * q0 + a01 * q1 + a02 * q2
        # scale-free test: det against the product of the diagonal
        if a00 > 0.0 and abs(det) > 1e-6 * a00 * a11 * a22:
            b0, b1, b2 = q0 / det, q1 / det, q2 / det
        elif a00 > 0.0:
            b0, b1, b2 = 1.0 / a00, 0.0, 0.0
        else:
            continue
        for c in range(4):
            stress[i, c] = b0 * r[6 + 3 * c] + b1 * r[7 + 3 * c] + b2 * r[8 + 3 * c]

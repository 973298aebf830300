"""Artificial stress against the tensile instability (Gray, Monaghan & Swift 2001, as used
for soils by Bui et al. 2008, refs. [11, 18] of Lian et al. 2023): the part of C_ij in
Eq. (26) of Lian et al. (2023) that adds f_ij^n (R_i + R_j) to the pair stress, with
f_ij = W(r_ij) / W(dx).

R_i is -epsilon times the tensile principal parts of particle i's EFFECTIVE stress sigma',
rotated back to the x, y (, z) axes; compression contributes nothing.

Why the effective stress and not the total stress sigma' - p I (Eq. 2): the tensile
instability is a clumping of the skeleton's particles, and any clump changes div v, which
the pore water of Eq. (25) already resists with its stiffness K_l / n. Under suction the
total stress is tensile while the skeleton is not, and an R built from it pushes the
particles of a sheared front or corner apart, so they dilate and the suction grows (in
the saturated sliding block the corner's pressure fell to -122 kPa with R from the total
stress, -76 kPa with R from sigma' or without artificial stress).
"""

import math

import numba as nb
import numpy as np


@nb.njit(cache=True)
def artificial_stress(n, stress, epsilon, out):
    """The artificial stress R of rows 0..n-1, written into `out`.

    Parameters
    ----------
    n : int
        number of rows to compute.
    stress : (cap, 4) or (cap, 6) float64 array
        effective stress sigma' (Pa), Voigt order xx, yy, zz, xy (2D) and yz, zx (3D).
    epsilon : float
        artificial stress coefficient (dimensionless).
    out : (cap, 3) or (cap, 6) float64 array
        R (Pa): (R_xx, R_yy, R_xy) in 2D; with 6 columns the 3D form
        (R_xx, R_yy, R_zz, R_xy, R_yz, R_zx) from the three principal stresses.
    """
    if out.shape[1] == 6:
        a, vec, r = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))  # once a call
        for i in range(n):
            _tensile_part_3d(stress, i, epsilon, out, a, vec, r)
        return
    for i in range(n):
        sxx = stress[i, 0]
        syy = stress[i, 1]
        sxy = stress[i, 3]
        c = 0.5 * (sxx + syy)
        d = 0.5 * (sxx - syy)
        rr = math.sqrt(d * d + sxy * sxy)
        s1 = c + rr
        s2 = c - rr
        r1 = -epsilon * s1 if s1 > 0.0 else 0.0
        r2 = -epsilon * s2 if s2 > 0.0 else 0.0
        if rr > 0.0:
            cos2 = d / rr
            sin2 = sxy / rr
        else:
            cos2 = 1.0
            sin2 = 0.0
        out[i, 0] = 0.5 * (r1 + r2) + 0.5 * (r1 - r2) * cos2
        out[i, 1] = 0.5 * (r1 + r2) - 0.5 * (r1 - r2) * cos2
        out[i, 2] = 0.5 * (r1 - r2) * sin2


@nb.njit(cache=True)
def _tensile_part_3d(stress, i, epsilon, out, a, vec, r):
    """out[i] = -epsilon sum over the tensile principal stresses s_k of s_k n_k n_k^T,
    from sigma'_i (Voigt xx, yy, zz, xy, yz, zx): the eigenpairs by cyclic Jacobi
    rotations (converged to round-off in a few sweeps for 3 x 3). a, vec, r: 3 x 3
    scratch."""
    a[0, 0], a[1, 1], a[2, 2] = stress[i, 0], stress[i, 1], stress[i, 2]
    a[0, 1] = a[1, 0] = stress[i, 3]
    a[1, 2] = a[2, 1] = stress[i, 4]
    a[2, 0] = a[0, 2] = stress[i, 5]
    for m in range(3):
        for q in range(3):
            vec[m, q] = 1.0 if m == q else 0.0
            r[m, q] = 0.0
    scale = abs(a[0, 0]) + abs(a[1, 1]) + abs(a[2, 2]) + abs(a[0, 1]) + abs(a[1, 2]) \
        + abs(a[2, 0])
    for _ in range(50):
        off = abs(a[0, 1]) + abs(a[1, 2]) + abs(a[2, 0])
        if off <= 1e-15 * scale:
            break
        for p, q in ((0, 1), (1, 2), (0, 2)):
            if a[p, q] == 0.0:
                continue
            theta = 0.5 * (a[q, q] - a[p, p]) / a[p, q]
            t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
            c = 1.0 / math.sqrt(t * t + 1.0)
            sn = t * c
            for k in range(3):  # a <- J^T a J, vec <- vec J
                akp, akq = a[k, p], a[k, q]
                a[k, p] = c * akp - sn * akq
                a[k, q] = sn * akp + c * akq
            for k in range(3):
                apk, aqk = a[p, k], a[q, k]
                a[p, k] = c * apk - sn * aqk
                a[q, k] = sn * apk + c * aqk
            for k in range(3):
                vkp, vkq = vec[k, p], vec[k, q]
                vec[k, p] = c * vkp - sn * vkq
                vec[k, q] = sn * vkp + c * vkq
    for k in range(3):
        if a[k, k] > 0.0:
            for m in range(3):
                for q in range(3):
                    r[m, q] -= epsilon * a[k, k] * vec[m, k] * vec[q, k]
    out[i, 0], out[i, 1], out[i, 2] = r[0, 0], r[1, 1], r[2, 2]
    out[i, 3], out[i, 4], out[i, 5] = r[0, 1], r[1, 2], r[2, 0]

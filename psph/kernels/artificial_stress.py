"""Artificial stress against the tensile instability (Gray, Monaghan and Swift 2001, as
used for soils by Bui et al. 2008, the paper's refs. [11, 18]): the part of C_ij in
Eq. (26) that adds f_ij^n (R_i + R_j) to the pair stress, with f_ij = W(r_ij) / W(dx).

R_i is -epsilon times the tensile principal parts of particle i's in-plane EFFECTIVE
stress sigma', rotated back to x, y: compression contributes nothing.

Why the effective stress and not the total sigma' - p I (Eq. 2): the tensile instability
is a clumping of the skeleton's particles, and any clump changes div v, which the pore
water of Eq. (25) resists with its stiffness K_l / n. Under suction the total stress is
tensile while the skeleton is not; R from the total stress then pushed the particles of
a sheared front or corner apart, they dilated and the suction grew (issue 13, cause 2:
`python -m psph.app.sliding`, the sliding block's corner reached -122 kPa with R from
the total stress and -76 kPa with R from sigma' or with no artificial stress at all).
"""

import math

import numba as nb


@nb.njit(cache=True)
def artificial_stress(n, stress, epsilon, out):
    """out[i] = (R_xx, R_yy, R_xy) for rows 0..n-1 (Pa)."""
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

"""The kinematics of a 3D step (issue 37): the corrected velocity gradient of Eq. (22) from
the sums of `interactions.pair_sums` (3D layout, `sum_columns.sum_layout(3)`), and the
linear elastic Jaumann stress rate of Eq. (11) with the full spin. The 2D step keeps its
own spelt-out plane-strain form in `update.py`; these are its 3D counterparts, checked
against numpy in tests/test_kernels_3d.py.
"""

import numba as nb


@nb.njit(cache=True, inline="always")
def inverse_moment_3d(s, c):
    """Inverse of the 3x3 moment matrix in s[c:c + 9] (row-major), by cofactors; identity
    (no correction) where it is near-singular, as `_inverse_moment`."""
    a00, a01, a02 = s[c], s[c + 1], s[c + 2]
    a10, a11, a12 = s[c + 3], s[c + 4], s[c + 5]
    a20, a21, a22 = s[c + 6], s[c + 7], s[c + 8]
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    if abs(det) < 1e-3:
        return 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
    inv = 1.0 / det
    return (c00 * inv, (a02 * a21 - a01 * a22) * inv, (a01 * a12 - a02 * a11) * inv,
            c01 * inv, (a00 * a22 - a02 * a20) * inv, (a02 * a10 - a00 * a12) * inv,
            c02 * inv, (a01 * a20 - a00 * a21) * inv, (a00 * a11 - a01 * a10) * inv)


@nb.njit(cache=True, inline="always")
def _entry(s, gv, gs, mi, a, b):
    """L[a][b] = sum_n G[a, n] Minv[n, b], G = GV + GS on the diagonal (a == b)."""
    acc = 0.0
    for n in range(3):
        g = s[gv + 3 * a + n]
        if a == b:
            g += s[gs + 3 * a + n]
        acc += g * mi[3 * n + b]
    return acc


@nb.njit(cache=True, inline="always")
def velocity_gradient_3d(s, gv, gs, mi, correct_strain, dry):
    """L[a][b] = dv_a/dx_b = G[a, n] Minv[n, b] (Eq. 22) as 9 values, row-major, from the
    sums' GV at column gv and GS at gs and the inverse moment mi (9 values): the
    stretching (diagonal) from GV + GS, the shear from GV, as in 2D (`interactions.py`,
    "Walls"); without `correct_strain` the shear from the plain gradient GV, and with
    `dry` the stretching too (the 2D step's rules, `update.advance`)."""
    l00 = _entry(s, gv, gs, mi, 0, 0)
    l01 = _entry(s, gv, gs, mi, 0, 1)
    l02 = _entry(s, gv, gs, mi, 0, 2)
    l10 = _entry(s, gv, gs, mi, 1, 0)
    l11 = _entry(s, gv, gs, mi, 1, 1)
    l12 = _entry(s, gv, gs, mi, 1, 2)
    l20 = _entry(s, gv, gs, mi, 2, 0)
    l21 = _entry(s, gv, gs, mi, 2, 1)
    l22 = _entry(s, gv, gs, mi, 2, 2)
    if not correct_strain:
        l01, l02, l10 = s[gv + 1], s[gv + 2], s[gv + 3]
        l12, l20, l21 = s[gv + 5], s[gv + 6], s[gv + 7]
        if dry:
            l00 = s[gv] + s[gs]
            l11 = s[gv + 4] + s[gs + 4]
            l22 = s[gv + 8] + s[gs + 8]
    return l00, l01, l02, l10, l11, l12, l20, l21, l22


@nb.njit(cache=True, inline="always")
def jaumann_elastic_3d(stress, i, lg, lam, shear, dt):
    """stress[i] += dt (lambda tr(D) I + 2 mu D + W sigma - sigma W) (Eq. 11, linear
    elastic), D and W the symmetric and skew parts of the velocity gradient lg (9 values,
    row-major); stress in Voigt order xx, yy, zz, xy, yz, zx."""
    sxx, syy, szz = stress[i, 0], stress[i, 1], stress[i, 2]
    sxy, syz, szx = stress[i, 3], stress[i, 4], stress[i, 5]
    tr = lg[0] + lg[4] + lg[8]
    w01 = 0.5 * (lg[1] - lg[3])
    w12 = 0.5 * (lg[5] - lg[7])
    w20 = 0.5 * (lg[6] - lg[2])
    stress[i, 0] = sxx + dt * (lam * tr + 2.0 * shear * lg[0]
                               + 2.0 * (w01 * sxy - w20 * szx))
    stress[i, 1] = syy + dt * (lam * tr + 2.0 * shear * lg[4]
                               + 2.0 * (w12 * syz - w01 * sxy))
    stress[i, 2] = szz + dt * (lam * tr + 2.0 * shear * lg[8]
                               + 2.0 * (w20 * szx - w12 * syz))
    stress[i, 3] = sxy + dt * (shear * (lg[1] + lg[3]) + w01 * (syy - sxx) - w20 * syz
                               + w12 * szx)
    stress[i, 4] = syz + dt * (shear * (lg[5] + lg[7]) + w12 * (szz - syy) - w01 * szx
                               + w20 * sxy)
    stress[i, 5] = szx + dt * (shear * (lg[6] + lg[2]) + w20 * (sxx - szz) - w12 * sxy
                               + w01 * syz)

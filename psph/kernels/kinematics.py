"""The kinematics of a 3D step: the corrected velocity gradient of Eq. (22) of Lian et al.
(2023) from the sums of `interactions.pair_sums` (3D layout, `sum_columns.sum_layout(3)`),
and the linear elastic Jaumann stress rate of Eq. (11) with the full spin. The 2D step
keeps its spelt-out plane-strain form in `update.py`; these are its 3D counterparts,
checked against numpy in tests/test_kernels_3d.py.
"""

import numba as nb


@nb.njit(cache=True, inline="always")
def inverse_moment_3d(s, c):
    """Inverse of the 3x3 moment matrix M of Eq. (22), by cofactors.

    Parameters
    ----------
    s : (nsums,) float64 array
        a particle's row of the pair sums.
    c : int
        first column of M (row-major, dimensionless).

    Returns
    -------
    tuple of 9 float
        M^-1 row-major; the identity (no correction) where |det M| < 1e-3, e.g. a
        particle with too few neighbours.
    """
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
    """The velocity gradient L[a][b] = dv_a/dx_b = G[a, n] Minv[n, b] of Eq. (22): the
    stretching (diagonal) from GV + GS, the shear from GV, as in 2D (`interactions.py`:
    a fixed wall resists shear, not stretching along itself).

    Parameters
    ----------
    s : (nsums,) float64 array
        a particle's row of the pair sums.
    gv, gs : int
        first columns of GV and GS (3x3, row-major; 1/s).
    mi : tuple of 9 float
        M^-1 of `inverse_moment_3d`.
    correct_strain : bool
        False: the shear from the plain gradient GV (Bui et al. 2008), as the 2D step.
    dry : bool
        with correct_strain False, the stretching from the plain gradient too.

    Returns
    -------
    tuple of 9 float
        L row-major (1/s).
    """
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
    """stress[i] += dt (lambda tr(D) I + 2 mu D + W sigma - sigma W): the linear elastic
    Jaumann rate of Eq. (11), D and W the symmetric and skew parts of the velocity
    gradient.

    Parameters
    ----------
    stress : (cap, 6) float64 array
        effective stress (Pa), Voigt order xx, yy, zz, xy, yz, zx; row i is updated.
    i : int
        the particle's row.
    lg : tuple of 9 float
        velocity gradient L row-major (1/s).
    lam, shear : float
        Lame constants lambda and mu (Pa).
    dt : float
        time step (s).
    """
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

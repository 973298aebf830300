"""Drucker-Prager strain-softening plasticity (Section 2.2 of Lian et al. 2023), per
particle, in 3D and in plane strain.

Stress components (xx, yy, zz, xy, yz, zx), effective, tension positive; plane strain is
the case yz = zx = 0 (`dp_return`: the zero components add nothing to J2). Yield function
Eq. (14) f = xi_phi I1 + sqrt(J2) - kappa_c and plastic potential Eq. (15)
g = xi_psi I1 + sqrt(J2), with the plane-strain constants of Eq. (16) or, with
`mohr_coulomb`, the cone through Mohr-Coulomb at each trial stress's Lode angle
(`mc_constants`: in 3D the plane-strain cone is a third weaker in triaxial compression),
and the softening laws of Eq. (17)-(19) in the equivalent plastic strain. The return
mapping is the semi-implicit one of Bui et al. (2008): one plastic corrector with the
multiplier of Eq. (13), then the tension-cracking treatment at the apex and the scaling
back of the deviator onto the surface, so that no state ends outside it and none is NaN.

An optional tension cut-off (`plasticity.tension_cutoff`) caps the mean effective stress
at t below the apex c cot(phi) with the same shift: without it a contractive soil
(psi < 0) at low confinement flows undrained until sigma'_m is tensile up to the apex,
moving its total stress onto the water, and p exceeds the total stress.
The strain that softens Eq. (17)-(19) is the particle's own eps_p (the local law) or, with
`plasticity.regularisation`, the over-non-local strain of `nonlocal_strain.py`;
`dp_return` returns the local increment either way.
"""

import math

import numba as nb

SQRT3 = math.sqrt(3.0)


@nb.njit(cache=True, inline="always")
def dp_constants(phi, c):
    """The plane-strain Drucker-Prager constants of Eq. (16).

    Parameters
    ----------
    phi : float
        friction (or dilatancy) angle (rad).
    c : float
        cohesion (Pa).

    Returns
    -------
    xi : float
        xi_phi (dimensionless).
    kappa : float
        kappa_c (Pa).
    """
    t = math.tan(phi)
    d = math.sqrt(9.0 + 12.0 * t * t)
    return t / d, 3.0 * c / d


@nb.njit(cache=True, inline="always")
def mc_constants(phi, c, sin_t, cos_t):
    """(xi, kappa) of the cone through the Mohr-Coulomb surface at Lode angle theta
    (sin_t, cos_t; +30 deg is triaxial compression): MC in invariants,
    I1 sin(phi) / 3 + sqrt(J2) a - c cos(phi) = 0 with a = cos(theta) - sin(theta)
    sin(phi) / sqrt(3), divided by a. The apex kappa / xi = 3 c cot(phi) for every theta;
    at theta = 0 xi = sin(phi) / 3, near Eq. (16)'s plane-strain fit; at +30 deg the
    compression cone.

    Parameters
    ----------
    phi : float
        friction (or dilatancy) angle (rad).
    c : float
        cohesion (Pa).
    sin_t, cos_t : float
        sine and cosine of the Lode angle theta (`lode_sin_cos`).

    Returns
    -------
    xi : float
        dimensionless.
    kappa : float
        Pa.
    """
    a = cos_t - sin_t * math.sin(phi) / SQRT3
    return math.sin(phi) / (3.0 * a), c * math.cos(phi) / a


@nb.njit(cache=True, inline="always")
def lode_sin_cos(dxx, dyy, dzz, sxy, syz, szx, j2):
    """The Lode angle theta of a deviator, sin(3 theta) = -(3 sqrt(3) / 2) J3 / J2^(3/2)
    (tension positive: +30 deg is triaxial compression).

    Parameters
    ----------
    dxx, dyy, dzz : float
        the deviator's diagonal (Pa).
    sxy, syz, szx : float
        the shear components (Pa).
    j2 : float
        J2 (Pa^2).

    Returns
    -------
    sin_t, cos_t : float
        sin(theta), cos(theta); theta = 0 where J2 vanishes (the apex, where the cone's
        theta does not matter).
    """
    if not j2 > 0.0:
        return 0.0, 1.0
    j3 = dxx * (dyy * dzz - syz * syz) - sxy * (sxy * dzz - syz * szx) \
        + szx * (sxy * syz - dyy * szx)
    s3 = -1.5 * SQRT3 * j3 / (j2 * math.sqrt(j2))
    theta = math.asin(min(max(s3, -1.0), 1.0)) / 3.0
    return math.sin(theta), math.cos(theta)


@nb.njit(cache=True, inline="always")
def softened(eps_p, phi_p, phi_r, c_p, c_r, psi0, eta, s_f):
    """The strength parameters after softening, Eq. (17)-(19).

    Parameters
    ----------
    eps_p : float
        equivalent plastic strain (dimensionless).
    phi_p, phi_r : float
        peak and residual friction angles (rad).
    c_p, c_r : float
        peak and residual cohesion (Pa).
    psi0 : float
        initial dilatancy angle (rad).
    eta : float
        softening rate of phi and c (dimensionless).
    s_f : float
        decay rate of psi (dimensionless).

    Returns
    -------
    phi, c, psi : float
        rad, Pa, rad.
    """
    decay = math.exp(-eta * eps_p)
    return (phi_r + (phi_p - phi_r) * decay, c_r + (c_p - c_r) * decay,
            psi0 * math.exp(-s_f * eps_p))


@nb.njit(cache=True, inline="always")
def _invariants(sxx, syy, szz, sxy, syz, szx):
    i1 = sxx + syy + szz
    m = i1 / 3.0
    dxx = sxx - m
    dyy = syy - m
    dzz = szz - m
    j2 = 0.5 * (dxx * dxx + dyy * dyy + dzz * dzz) + sxy * sxy + syz * syz + szx * szx
    return i1, dxx, dyy, dzz, j2


@nb.njit(cache=True)
def dp_return(sxx, syy, szz, sxy, eps_p, bulk, shear, law, eps_dilation=-1.0):
    """`dp_return_3d` in plane strain (yz = zx = 0).

    Parameters
    ----------
    sxx, syy, szz, sxy : float
        the elastic trial effective stress (Pa).
    eps_p, bulk, shear, law, eps_dilation
        as `dp_return_3d`.

    Returns
    -------
    tuple
        (sxx, syy, szz, sxy, d_lambda, d_eps_p, d_w), as `dp_return_3d`.
    """
    r = dp_return_3d(sxx, syy, szz, sxy, 0.0, 0.0, eps_p, bulk, shear, law, eps_dilation)
    return r[0], r[1], r[2], r[3], r[6], r[7], r[8]


@nb.njit(cache=True)
def dp_return_3d(sxx, syy, szz, sxy, syz, szx, eps_p, bulk, shear, law, eps_dilation=-1.0):
    """Return the trial stress to the Drucker-Prager surface.

    A trial state with f <= 0 and sigma'_m <= tension is returned unchanged (d_lambda = 0,
    d_w = 0). Inside the cone but above the cut-off only the mean moves (d_lambda = 0);
    where the Eq. (13) return would end above the cut-off (the corner) the mean goes to
    the cut-off and d_lambda returns the deviator alone. d_w counts the cone's flow, not
    the cut-off's own volume change (exact at t = 0).

    Eq. (13) with a:D:b = 9 K xi_phi xi_psi + G for Eq. (14)-(15), and the softening term
    with the sign that keeps f = 0 to first order after the update (softening makes
    df/d eps_p > 0 and enlarges d_lambda); the denominator is kept positive.

    mohr_coulomb: instead of Eq. (16)'s plane-strain cone, the cone through the
    Mohr-Coulomb surface at the trial stress's Lode angle (`mc_constants`, for phi and
    psi alike): every return here keeps the deviator's direction, so the Lode angle and
    with it the cone are the trial's, and the returned stress lies on Mohr-Coulomb (a
    return radial in the deviatoric plane). In plane strain at failure with psi = 0 the
    Lode angle is 0 and xi = sin(phi) / 3; in triaxial compression the plane-strain cone
    is the weaker by a third (phi = 30 deg: xi 0.160 against 0.231). The flow stays
    radial in the deviatoric plane (it ignores d a / d theta), so psi = phi is not the
    associated Mohr-Coulomb flow.

    Parameters
    ----------
    sxx, syy, szz, sxy, syz, szx : float
        the elastic trial effective stress (Pa, tension positive).
    eps_p : float
        the equivalent plastic strain that softens phi and c (dimensionless): the
        particle's own or the regularised one.
    bulk, shear : float
        bulk modulus K and shear modulus G (Pa).
    law : `bundles.DruckerPrager`
        the material's law: the softening parameters of Eq. (17)-(19) phi_p, phi_r,
        c_p, c_r, psi0, eta, s_f, as `softened` (rad, Pa); the tension cut-off of the
        mean effective stress (Pa; inf: none, the apex c cot(phi) of Eq. 14 bounds it);
        mohr_coulomb: the Lode-dependent cone (above) instead of Eq. (16).
    eps_dilation : float
        >= 0: the strain whose Eq. (19) decays psi, the particle's own eps_p when eps_p
        here is the regularised one (`update.advance`); < 0: eps_p, as for phi and c.

    Returns
    -------
    tuple
        (sxx, syy, szz, sxy, syz, szx, d_lambda, d_eps_p, d_w): the corrected stress (Pa),
        the plastic multiplier of Eq. (13), the increment of the equivalent plastic
        strain d_eps_p = sqrt(2/3 de_p:de_p) of the deviatoric plastic strain
        = d_lambda / sqrt(3), and the plastic work increment d_w = sigma : d eps_p
        (J/m^3, `plastic_work_increment`).
    """
    phi_p, phi_r, c_p, c_r, psi0 = law.phi_p, law.phi_r, law.c_p, law.c_r, law.psi0
    eta, s_f, tension, mohr_coulomb = law.eta, law.s_f, law.tension, law.mohr_coulomb
    phi, c, psi = softened(eps_p, phi_p, phi_r, c_p, c_r, psi0, eta, s_f)
    if eps_dilation >= 0.0:
        psi = psi0 * math.exp(-s_f * eps_dilation)
    i1, dxx, dyy, dzz, j2 = _invariants(sxx, syy, szz, sxy, syz, szx)
    sin_t, cos_t = 0.0, 1.0
    if mohr_coulomb:
        sin_t, cos_t = lode_sin_cos(dxx, dyy, dzz, sxy, syz, szx, j2)
        xi, kap = mc_constants(phi, c, sin_t, cos_t)
        xi_psi = mc_constants(psi, 0.0, sin_t, cos_t)[0]
    else:
        xi, kap = dp_constants(phi, c)
        xi_psi = dp_constants(psi, 0.0)[0]
    rj2 = math.sqrt(j2)
    f = xi * i1 + rj2 - kap
    if not f > 0.0 and not i1 > 3.0 * tension:
        return sxx, syy, szz, sxy, syz, szx, 0.0, 0.0, 0.0
    d_lam = 0.0
    if f > 0.0 and rj2 > 1e-12 * (abs(i1) + kap + 1.0):
        # df/d eps_p of the softened surface: d(xi)/d eps I1 - d(kappa)/d eps
        decay = math.exp(-eta * eps_p)
        dphi = -eta * (phi_p - phi_r) * decay
        dc = -eta * (c_p - c_r) * decay
        if mohr_coulomb:
            sp, cp = math.sin(phi), math.cos(phi)
            a = cos_t - sin_t * sp / SQRT3
            da = -sin_t * cp / SQRT3 * dphi
            dxi = (cp * dphi * a - sp * da) / (3.0 * a * a)
            dkap = dc * cp / a - c * (sp * dphi * a + cp * da) / (a * a)
        else:
            t = math.tan(phi)
            d = math.sqrt(9.0 + 12.0 * t * t)
            dt_dphi = 1.0 + t * t
            dxi = dt_dphi * dphi * (1.0 / d - 12.0 * t * t / (d * d * d))
            dkap = 3.0 * dc / d - 3.0 * c * 12.0 * t * dt_dphi * dphi / (d * d * d)
        dfde = dxi * i1 - dkap
        elastic = 9.0 * bulk * xi * xi_psi + shear
        denom = elastic - dfde / math.sqrt(3.0)
        if denom < 0.1 * elastic:
            denom = 0.1 * elastic
        d_lam = f / denom
        if i1 - 9.0 * bulk * xi_psi * d_lam > 3.0 * tension:
            # the corner of the cone and the cut-off: the mean goes to the cut-off and
            # only the deviator returns, onto the cone at I1 = 3 t (Eq. 13 without its
            # volumetric part)
            i1c = 3.0 * tension
            fc = xi * i1c + rj2 - kap
            d_lam = 0.0
            r = 1.0
            if fc > 0.0:
                denom = shear - (dxi * i1c - dkap) / math.sqrt(3.0)
                if denom < 0.1 * shear:
                    denom = 0.1 * shear
                d_lam = fc / denom
                r = max(1.0 - d_lam * shear / rj2, 0.0)
            sxx = tension + r * dxx
            syy = tension + r * dyy
            szz = tension + r * dzz
            sxy = r * sxy
            syz = r * syz
            szx = r * szx
        else:
            shift = d_lam * 3.0 * bulk * xi_psi
            scale = d_lam * shear / rj2
            sxx = sxx - shift - scale * dxx
            syy = syy - shift - scale * dyy
            szz = szz - shift - scale * dzz
            sxy = sxy - scale * sxy
            syz = syz - scale * syz
            szx = szx - scale * szx
    d_eps = d_lam / math.sqrt(3.0)
    # the surface at the updated plastic strain
    phi, c, psi = softened(eps_p + d_eps, phi_p, phi_r, c_p, c_r, psi0, eta, s_f)
    if mohr_coulomb:
        xi, kap = mc_constants(phi, c, sin_t, cos_t)
    else:
        xi, kap = dp_constants(phi, c)
    i1, dxx, dyy, dzz, j2 = _invariants(sxx, syy, szz, sxy, syz, szx)
    # tension cracking: beyond the apex I1 = kappa / xi, move the mean stress back to it
    if xi > 0.0 and xi * i1 > kap:
        shift = (i1 - kap / xi) / 3.0
        sxx -= shift
        syy -= shift
        szz -= shift
        i1 = kap / xi
    # tension cut-off: sigma'_m at most `tension`, the same shift
    if i1 > 3.0 * tension:
        shift = (i1 - 3.0 * tension) / 3.0
        sxx -= shift
        syy -= shift
        szz -= shift
        i1 = 3.0 * tension
    # scaling back: a deviator still outside the surface is scaled onto it
    room = kap - xi * i1
    rj2 = math.sqrt(j2)
    if rj2 > room:
        r = room / rj2 if rj2 > 0.0 and room > 0.0 else 0.0
        m = i1 / 3.0
        sxx = m + r * dxx
        syy = m + r * dyy
        szz = m + r * dzz
        sxy = r * sxy
        syz = r * syz
        szx = r * szx
    d_w = plastic_work_increment(sxx, syy, szz, sxy, syz, szx, d_lam, xi_psi)
    return sxx, syy, szz, sxy, syz, szx, d_lam, d_eps, d_w


@nb.njit(cache=True, inline="always")
def plastic_work_increment(sxx, syy, szz, sxy, syz, szx, d_lam, xi_psi):
    """sigma : d eps_p (J/m^3) of one return: d eps_p = d_lambda dg/dsigma with the
    potential g = xi_psi I1 + sqrt(J2) of Eq. (15), homogeneous of degree 1 in sigma, so
    sigma : dg/dsigma = g and d_w = d_lambda (xi_psi I1 + sqrt(J2)) at the returned stress
    (xi_psi of Eq. 16, or of `mc_constants`, at the softened psi of Eq. 19 that set the
    flow direction).

    Parameters
    ----------
    sxx, syy, szz, sxy, syz, szx : float
        the returned effective stress (Pa).
    d_lam : float
        the plastic multiplier of Eq. (13).
    xi_psi : float
        the potential's constant (dimensionless).

    Returns
    -------
    float
        d_w (J/m^3).
    """
    if d_lam == 0.0:
        return 0.0
    i1, _, _, _, j2 = _invariants(sxx, syy, szz, sxy, syz, szx)
    return d_lam * (xi_psi * i1 + math.sqrt(j2))

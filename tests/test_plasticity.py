"""Drucker-Prager return mapping (Eq. 13-19): lands on the yield surface, agrees with the
multiplier of Eq. (13), leaves elastic states alone, softens to the residual values, and
keeps apex / tension states finite."""

import math

import numpy as np
import pytest

from psph.kernels.bundles import DruckerPrager
from psph.kernels.plasticity import dp_constants, dp_return, softened

E, NU = 20e6, 0.3
K = E / (3 * (1 - 2 * NU))
G = E / (2 * (1 + NU))
PHI, C = math.radians(30.0), 5e3


def f_of(s, phi, c):
    xi, kap = dp_constants(phi, c)
    i1 = s[0] + s[1] + s[2]
    d = np.array(s[:3]) - i1 / 3
    j2 = 0.5 * np.sum(d * d) + s[3] ** 2
    return xi * i1 + math.sqrt(j2) - kap


def ret(s, eps=0.0, phi_p=PHI, phi_r=PHI, c_p=C, c_r=C, psi0=0.0, eta=0.0, s_f=0.0):
    return dp_return(*s, eps, K, G, DruckerPrager(phi_p, phi_r, c_p, c_r, psi0, eta, s_f))


def test_plane_strain_constants_eq16():
    xi, kap = dp_constants(math.radians(30), 1e4)
    t = math.tan(math.radians(30))
    assert xi == pytest.approx(t / math.sqrt(9 + 12 * t * t))
    assert kap == pytest.approx(3e4 / math.sqrt(9 + 12 * t * t))


def test_elastic_state_untouched():
    s = (-50e3, -80e3, -40e3, 5e3)
    assert f_of(s, PHI, C) < 0
    out = ret(s)
    assert out[:4] == s and out[4] == 0.0 and out[5] == 0.0


@pytest.mark.parametrize("psi_deg", [30.0, 10.0, 0.0])
def test_return_lands_on_the_surface_with_the_eq13_multiplier(psi_deg):
    s = (-50e3, -120e3, -60e3, 40e3)  # a big deviator: outside
    f_trial = f_of(s, PHI, C)
    assert f_trial > 1e3
    psi = math.radians(psi_deg)
    out = ret(s, psi0=psi)
    assert abs(f_of(out[:4], PHI, C)) < 1e-9 * 1e5
    xi_phi = dp_constants(PHI, C)[0]
    xi_psi = dp_constants(psi, 0.0)[0]
    d_lam = f_trial / (9 * K * xi_phi * xi_psi + G)  # Eq. (13), no softening
    assert out[4] == pytest.approx(d_lam, rel=1e-12)
    assert out[5] == pytest.approx(d_lam / math.sqrt(3), rel=1e-12)
    # plastic flow along dg/dsigma (Eq. 12, 15): volumetric part 3 K xi_psi d_lam
    i1_trial, i1_out = sum(s[:3]), sum(out[:3])
    assert i1_trial - i1_out == pytest.approx(9 * K * xi_psi * d_lam, rel=1e-9, abs=1e-6)


def test_return_with_softening_ends_on_the_softened_surface():
    phi_r, c_r, eta = math.radians(20.0), 1e3, 30.0
    s = (-50e3, -120e3, -60e3, 40e3)
    eps0 = 0.01
    out = ret(s, eps=eps0, phi_r=phi_r, c_r=c_r, eta=eta, psi0=math.radians(5), s_f=10.0)
    phi, c, _ = softened(eps0 + out[5], PHI, phi_r, C, c_r, math.radians(5), eta, 10.0)
    f_after = f_of(out[:4], phi, c)
    assert out[5] > 0
    assert f_after <= 1e-9 * 1e5  # never outside
    assert abs(f_after) < 0.02 * f_of(s, PHI, C)  # first-order consistent (Eq. 13)


def test_softening_laws_reach_residual_values():
    phi_p, phi_r, c_p, c_r, psi0 = 0.6, 0.3, 1e4, 1e3, 0.1
    assert softened(0.0, phi_p, phi_r, c_p, c_r, psi0, 20.0, 5.0) == (phi_p, c_p, psi0)
    phi, c, psi = softened(50.0, phi_p, phi_r, c_p, c_r, psi0, 20.0, 5.0)
    assert phi == pytest.approx(phi_r) and c == pytest.approx(c_r) and psi < 1e-100
    a = softened(0.01, phi_p, phi_r, c_p, c_r, psi0, 20.0, 5.0)
    b = softened(0.02, phi_p, phi_r, c_p, c_r, psi0, 20.0, 5.0)
    assert phi_p > a[0] > b[0] > phi_r and c_p > a[1] > b[1] > c_r  # monotone


@pytest.mark.parametrize("s", [(1e6, 1e6, 1e6, 0.0), (1e9, -1e3, 2e8, 5e8),
                               (0.0, 0.0, 0.0, 1e12), (1e300, 1e300, 1e300, 0.0)])
def test_apex_and_tension_states_are_finite_and_not_outside(s):
    out = ret(s)
    assert all(math.isfinite(v) for v in out)
    xi, kap = dp_constants(PHI, C)
    assert f_of(out[:4], PHI, C) <= 1e-9 * max(1.0, abs(sum(out[:3])))
    assert sum(out[:3]) <= kap / xi * (1 + 1e-12)


def test_cohesionless_material_at_zero_stress_stays_finite():
    out = dp_return(0.0, 0.0, 0.0, 10.0, 0.0, K, G,
                    DruckerPrager(PHI, PHI, 0.0, 0.0, 0.0, 0.0, 0.0))
    assert all(math.isfinite(v) for v in out)
    assert out[:4] == pytest.approx((0.0, 0.0, 0.0, 0.0), abs=1e-9)


def test_random_states_never_end_outside():
    rng = np.random.default_rng(7)
    law = (PHI, math.radians(22), C, 500.0, math.radians(5), 15.0, 8.0)
    inside = outside = 0
    for s in rng.normal(0.0, 1e5, (2000, 4)) + np.array([-2e5, -2e5, -2e5, 0.0]):
        s = tuple(float(v) for v in s)
        eps = float(rng.uniform(0, 0.2))
        out = dp_return(*s, eps, K, G, DruckerPrager(*law))
        assert all(math.isfinite(v) for v in out) and out[5] >= 0.0
        phi0, c0, _ = softened(eps, *law)
        phi1, c1, _ = softened(eps + out[5], *law)
        if f_of(s, phi0, c0) <= 0.0:
            inside += 1
            assert out[:4] == s and out[5] == 0.0
        else:
            outside += 1
            assert f_of(out[:4], phi1, c1) <= 1e-9 * max(1e5, abs(sum(out[:3])))
    assert inside > 100 and outside > 100


def _as(sxx, syy, sxy, eps=0.5):
    from psph.kernels.artificial_stress import artificial_stress

    out = np.zeros((1, 3))
    artificial_stress(1, np.array([[sxx, syy, 0.0, sxy]]), eps, out)
    return out[0]


def test_artificial_stress_acts_on_effective_tension_only():
    """Tension of the skeleton only: compressive sigma' gives nothing whatever the pore
    pressure (suction makes the total stress tensile, not the skeleton; issue 13)."""
    assert np.all(_as(-1e4, -2e4, 3e3) == 0.0)  # both principal stresses compressive
    assert _as(1e4, -2e4, 0.0) == pytest.approx([-0.5e4, 0.0, 0.0])


def test_artificial_stress_rotates_with_the_stress():
    t, th = 2e4, 0.3  # uniaxial tension t along an axis at angle th
    c, s = math.cos(th), math.sin(th)
    r = _as(t * c * c, t * s * s, t * s * c)
    assert r == pytest.approx([-0.5 * t * c * c, -0.5 * t * s * s, -0.5 * t * s * c])


def test_tension_cutoff_moves_the_mean_stress_and_keeps_the_deviator():
    """An elastic trial state (f < 0) with sigma'_m = 5 kPa above a cut-off of 1 kPa: the
    mean moves to the cut-off, the deviator stays, no plastic strain; without the cut-off
    (the default) the state is left alone, below the apex c cot(phi) = 8.7 kPa."""
    s = (6e3, 4e3, 5e3, 0.5e3)
    assert f_of(s, PHI, C) < 0
    assert ret(s)[:5] == (*s, 0.0)
    out = dp_return(*s, 0.0, K, G, DruckerPrager(PHI, PHI, C, C, 0.0, 0.0, 0.0, 1e3))
    assert sum(out[:3]) / 3 == pytest.approx(1e3, rel=1e-12)
    assert np.allclose(np.subtract(out[:3], 1e3), np.subtract(s[:3], 5e3), atol=1e-9)
    assert out[3] == s[3] and out[5] == 0.0 and out[6] == 0.0


def test_tension_cutoff_corner_returns_the_deviator_alone():
    """Pure shear at sigma'_m = 0 with a cut-off at 0 (the liquefied debris of the slopes):
    the Eq. (13) return would shift the mean by -3 K xi_psi d_lambda (contractive psi:
    into tension, above the cut-off), so the mean stays at the cut-off and only the deviator
    returns, onto the cone at I1 = 0: sqrt J2 = kappa, d_lambda = (sqrt J2 - kappa) / G.
    Without the corner rule d_lambda took the volumetric part too and the state ended
    inside the cone."""
    psi = math.radians(-10.0)
    tau = 3 * C
    out = ret((0.0, 0.0, 0.0, tau), psi0=psi)
    assert sum(out[:3]) > 0.0  # without a cut-off the return goes into tension
    cut = dp_return(0.0, 0.0, 0.0, tau, 0.0, K, G,
                    DruckerPrager(PHI, PHI, C, C, psi, 0.0, 0.0, 0.0))
    kap = dp_constants(PHI, C)[1]
    assert cut[:3] == (0.0, 0.0, 0.0)
    assert cut[3] == pytest.approx(kap, rel=1e-12)
    assert cut[4] == pytest.approx((tau - kap) / G, rel=1e-12)
    assert f_of(cut[:4], PHI, C) == pytest.approx(0.0, abs=1e-9 * C)


# Returns of `dp_return` before the tension cut-off existed (psph/kernels/plasticity.py at
# 384cc64, compiled and as plain Python: the same bits), on the softening law below:
# (trial sxx, syy, szz, sxy), eps_p -> (sxx, syy, szz, sxy, d_lambda, d_eps_p, d_w);
# three elastic states, three cone returns and three apex returns.
PAPER_LAW_RETURNS = [
    (  # elastic
        (-57130.382723799456, -92761.66110189824, -77723.05610498221, -9854.514782871736),
        0.7252082462632354,
        (-57130.382723799456, -92761.66110189824, -77723.05610498221, -9854.514782871736, 0.0,
         0.0, 0.0)),
    (  # elastic
        (-85935.42515203838, -119139.39003013316, -120961.47536041691, -16850.631843885927),
        0.4894678447395572,
        (-85935.42515203838, -119139.39003013316, -120961.47536041691, -16850.631843885927, 0.0,
         0.0, 0.0)),
    (  # elastic
        (-109784.52490164102, -49774.66811503811, -107182.35016542421, 6799.419369203316),
        0.21439025116032873,
        (-109784.52490164102, -49774.66811503811, -107182.35016542421, 6799.419369203316, 0.0,
         0.0, 0.0)),
    (  # cone
        (102455.14728311096, -173339.9018788509, 5085.930803546729, -22710.784245117193),
        0.09412864224039919,
        (4555.424318174133, 1803.6127583182533, 3583.8994982154363, -226.60232230059046,
         0.018237259794808704, 0.010529286851813945, 20.76412258854916)),
    (  # cone
        (-32935.829785385955, -141199.16774883505, -33915.94265865137, -34608.52305099767),
        0.11367201992140341,
        (-47100.056644354496, -90726.76026156562, -47495.01115654402, -13946.14101299037,
         0.005526257205415853, 0.003190586085157952, 186.6409225979168)),
    (  # cone
        (-6452.803206324694, -41157.847660495725, -36877.24508908103, -26721.853844358004),
        0.7378377872921602,
        (-18807.091729699947, -28919.091162288776, -27671.853146776557, -7785.939339991088,
         0.0030163792056072678, 0.0017415073463353456, 33.346563372044386)),
    (  # apex
        (-18544.426095400122, 72749.25107276872, 12706.331361258675, -20209.14942456072),
        0.8917110704451572,
        (2854.3519762689502, 2854.3519762689502, 2854.3519762689502, 4.539863037804624e-14,
         0.007747881984995424, 0.00447324174968656, -1.2343936318988031)),
    (  # apex
        (12431.507905288126, 96105.28204593116, -36177.21964051481, -9742.347163164182),
        0.7069650956556235,
        (3012.2928366830315, 3012.2928366830315, 3012.2928366830315, 0.0, 0.01018208081285493,
         0.005878627098212318, -1.8772512277178952)),
    (  # apex
        (-23164.838494572756, 64335.889961085544, 24844.479248761025, 7752.6258505848),
        0.47968392351227496,
        (3553.283343913094, 3553.283343913094, 3553.283343913094, -0.0, 0.006985416335123828,
         0.0040330320014853515, -1.7014759875066654)),
]


@pytest.mark.parametrize("trial, eps_p, before", PAPER_LAW_RETURNS)
def test_unset_tension_cutoff_returns_the_paper_law_bit_for_bit(trial, eps_p, before):
    """tension = inf (an unset `tension_cutoff`) and the tension left at its default (as
    `bench/studies/softening_band.py` sets the law) give the returns of the kernel before
    the cut-off was added, bit for bit (the sign of a zero too): elastic, cone and apex
    states with softening."""
    law = (PHI, math.radians(20.0), C, 1e3, math.radians(-5.0), 5.0, 0.5)
    bits = np.array(before).view(np.int64)
    assert (np.array(dp_return(*trial, eps_p, K, G, DruckerPrager(*law, math.inf)))
            .view(np.int64) == bits).all()
    assert (np.array(dp_return(*trial, eps_p, K, G, DruckerPrager(*law))).view(np.int64)
            == bits).all()


def test_tension_cutoff_reaches_the_material_table():
    """The scene key lands in the kernels' column: 0 in the slopes that set it, inf (no
    cut-off, the paper's law) in a Drucker-Prager scene without it."""
    from psph.config.load import load_scene
    from psph.kernels.update import MAT_TENSION
    from psph.physics.material import material_table

    assert material_table(load_scene("retrogressive_k0_0.5"))[0, MAT_TENSION] == 0.0
    assert material_table(load_scene("collapse_dry"))[0, MAT_TENSION] == math.inf
    sets = ["material.plasticity.tension_cutoff=2.5e3"]
    assert material_table(load_scene("collapse_dry", sets))[0, MAT_TENSION] == 2.5e3


def test_negative_tension_cutoff_exit_2_one_line(tmp_path):
    import subprocess
    import sys

    from tests.helpers import assert_bad_input

    out = tmp_path / "out"
    result = subprocess.run([sys.executable, "-m", "psph", "run", "collapse_dry", "--out",
                             str(out), "--set", "material.plasticity.tension_cutoff=-1.0"],
                            capture_output=True, text=True, timeout=120)
    assert_bad_input(result, ["material.plasticity.tension_cutoff", "-1", "greater than"], out)


def test_dilation_decays_with_its_own_strain():
    """eps_dilation drives psi of Eq. (19) alone: with the softening strain at 0 (peak phi
    and c, as a regularised eps_hat clipped to 0) and eps_dilation = 10, the return is
    that of psi_0 exp(-s_f 10) without decay; eps_dilation = eps_p gives the default's
    bits; a contractive state's volume change (d_lambda 3 xi_psi) shrinks with it."""
    psi0, s_f = math.radians(-5.0), 0.5
    law = DruckerPrager(phi_p=PHI, phi_r=math.radians(20.0), c_p=C, c_r=1e3, psi0=psi0,
                        eta=5.0, s_f=s_f)
    s = (-20e3, -120e3, -60e3, 45e3)
    own = dp_return(*s, 0.0, K, G, law, 10.0)
    decayed = dp_return(*s, 0.0, K, G,
                        law._replace(psi0=psi0 * math.exp(-s_f * 10.0), s_f=0.0))
    assert own[4] > 0.0
    assert np.allclose(own, decayed, rtol=1e-12, atol=1e-9)
    peak = dp_return(*s, 0.0, K, G, law)
    mean = [sum(r[:3]) for r in (s, own, peak)]
    assert mean[2] - mean[0] > 100.0 * abs(mean[1] - mean[0])  # psi_0 contracts, ~0 not
    for eps in (0.0, 0.3, 2.0):
        a = dp_return(*s, eps, K, G, law, eps)
        b = dp_return(*s, eps, K, G, law)
        assert np.array_equal(np.array(a).view(np.int64), np.array(b).view(np.int64))


def test_return_in_3d_is_isotropic_and_plane_strain_is_its_case():
    """`dp_return_3d`: returning a rotated trial stress gives the rotated return (the law
    is isotropic: all six components take part); with yz = zx = 0 it is `dp_return`, bit
    for bit; every returned state lies on or inside the softened surface."""
    from psph.kernels.plasticity import dp_return_3d

    rng = np.random.default_rng(11)
    voigt = [[0, 3, 5], [3, 1, 4], [5, 4, 2]]  # xx yy zz xy yz zx
    phi_p, phi_r, c_p, c_r = math.radians(30.0), math.radians(20.0), 5e3, 1e3
    psi0, eta, s_f = math.radians(-5.0), 5.0, 2.0
    args = (K, G, DruckerPrager(phi_p, phi_r, c_p, c_r, psi0, eta, s_f))
    for _ in range(40):
        trial = rng.normal(size=6) * 40e3 - [20e3, 20e3, 20e3, 0, 0, 0]
        eps = rng.uniform(0.0, 0.3)
        a = np.asarray(trial)[voigt]
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        b = q @ a @ q.T
        rb = dp_return_3d(b[0, 0], b[1, 1], b[2, 2], b[0, 1], b[1, 2], b[2, 0], eps, *args)
        ra = dp_return_3d(*trial, eps, *args)
        ret_a = np.asarray(ra[:6])[voigt]
        ret_b = np.asarray(rb[:6])[voigt]
        assert np.allclose(q @ ret_a @ q.T, ret_b, rtol=1e-9, atol=1e-6)
        assert ra[6:] == pytest.approx(rb[6:], rel=1e-9, abs=1e-12)
        phi, c, _ = softened(eps + ra[7], phi_p, phi_r, c_p, c_r, psi0, eta, s_f)
        xi, kap = dp_constants(phi, c)
        dev = ret_a - np.trace(ret_a) / 3.0 * np.eye(3)
        f = xi * np.trace(ret_a) + np.sqrt(0.5 * np.sum(dev * dev)) - kap
        assert f <= 1e-6 * kap
        plane = dp_return(trial[0], trial[1], trial[2], trial[3], eps, *args)
        r3 = dp_return_3d(trial[0], trial[1], trial[2], trial[3], 0.0, 0.0, eps, *args)
        assert plane == (r3[0], r3[1], r3[2], r3[3], r3[6], r3[7], r3[8])

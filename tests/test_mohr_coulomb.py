"""The Lode-dependent Mohr-Coulomb cone of `dp_return_3d` (`plasticity.surface =
"mohr_coulomb"`, issue 37): every return lands on the Mohr-Coulomb surface of the
principal stresses, keeps the trial's Lode angle, matches the compression cone in
triaxial compression and sin(phi) / 3 at theta = 0, ends on the softened surface, and
the default (plane-strain) return is untouched by the flag."""

import math

import numpy as np
import pytest

from psph.kernels.bundles import DruckerPrager
from psph.kernels.plasticity import dp_return_3d, lode_sin_cos, mc_constants

E, NU = 20e6, 0.3
K = E / (3 * (1 - 2 * NU))
G = E / (2 * (1 + NU))
PHI, C = math.radians(30.0), 5e3


def mohr_coulomb(s, phi, c):
    """(sigma_1 - sigma_3) / 2 + (sigma_1 + sigma_3) / 2 sin(phi) - c cos(phi) of the
    principal stresses of s (xx, yy, zz, xy, yz, zx; tension positive)."""
    m = np.array([[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]])
    ev = np.linalg.eigvalsh(m)
    return 0.5 * (ev[2] - ev[0]) + 0.5 * (ev[2] + ev[0]) * math.sin(phi) - c * math.cos(phi)


def deviator_direction(s):
    s = np.asarray(s[:6], dtype=float)
    d = s.copy()
    d[:3] -= s[:3].mean()
    return d / math.sqrt(0.5 * np.sum(d[:3] ** 2) + np.sum(d[3:] ** 2))


def ret(s, eps=0.0, phi_r=PHI, c_r=C, psi0=0.0, eta=0.0, s_f=0.0, mc=True):
    law = DruckerPrager(PHI, phi_r, C, c_r, psi0, eta, s_f, math.inf, mc)
    return dp_return_3d(*s, eps, K, G, law, -1.0)


def random_trials(n, seed=3):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        mean = rng.uniform(-200e3, -10e3)
        dev = rng.normal(0.0, 1.0, 6) * rng.uniform(20e3, 300e3)
        out.append(tuple(float(v) for v in np.r_[dev[:3] - dev[:3].mean() + mean, dev[3:]]))
    return out


def test_the_cone_is_mohr_coulomb_at_its_lode_angle():
    # triaxial compression (theta = +30 deg, tension positive): the compression cone
    xi, kap = mc_constants(PHI, C, math.sin(math.radians(30)), math.cos(math.radians(30)))
    s = math.sin(PHI)
    assert xi == pytest.approx(2 * s / (math.sqrt(3) * (3 - s)), rel=1e-14)
    assert kap == pytest.approx(6 * C * math.cos(PHI) / (math.sqrt(3) * (3 - s)), rel=1e-14)
    # theta = 0: sin(phi) / 3; the apex 3 c cot(phi) for every theta
    assert mc_constants(PHI, C, 0.0, 1.0)[0] == pytest.approx(s / 3, rel=1e-14)
    for t in np.radians([-30.0, -10.0, 0.0, 17.0, 30.0]):
        xi, kap = mc_constants(PHI, C, math.sin(t), math.cos(t))
        assert kap / xi == pytest.approx(3 * C / math.tan(PHI), rel=1e-12)
    # the Lode angle of a triaxial compression state
    st, ct = lode_sin_cos(50.0, 50.0, -100.0, 0.0, 0.0, 0.0, 0.5 * (2 * 50 ** 2 + 100 ** 2))
    assert math.degrees(math.atan2(st, ct)) == pytest.approx(30.0, abs=1e-6)


@pytest.mark.parametrize("psi_deg", [0.0, 10.0])
def test_returns_land_on_mohr_coulomb_and_keep_the_lode_angle(psi_deg):
    landed = 0
    for trial in random_trials(300):
        out = ret(trial, psi0=math.radians(psi_deg))
        f_trial = mohr_coulomb(trial, PHI, C)
        f_out = mohr_coulomb(out[:6], PHI, C)
        assert f_out <= 1e-6 * 1e5  # never outside
        if f_trial <= 0.0:
            assert out[6] == 0.0 and out[:6] == trial
            continue
        i1 = sum(out[:3])
        if i1 < 3 * C / math.tan(PHI) - 1.0:  # not at the apex
            assert abs(f_out) < 1e-8 * 1e5
            assert np.allclose(deviator_direction(out), deviator_direction(trial), atol=1e-9)
            landed += 1
    assert landed > 100


def test_softening_ends_on_the_softened_mohr_coulomb_surface():
    from psph.kernels.plasticity import softened

    phi_r, c_r, eta = math.radians(20.0), 1e3, 30.0
    for trial in random_trials(50, seed=7):
        if mohr_coulomb(trial, PHI, C) < 1e3:
            continue
        out = ret(trial, eps=0.01, phi_r=phi_r, c_r=c_r, eta=eta)
        phi, c, _ = softened(0.01 + out[7], PHI, phi_r, C, c_r, 0.0, eta, 0.0)
        f_after = mohr_coulomb(out[:6], phi, c)
        assert f_after <= 1e-6 * 1e5
        if sum(out[:3]) < 3 * c / math.tan(phi) - 1.0:
            assert abs(f_after) < 0.02 * mohr_coulomb(trial, PHI, C)


def test_the_softening_multiplier_is_eq13_with_the_cone_s_derivative():
    """With softening, d_lambda = f / (G - (d xi / d eps I1 - d kappa / d eps) / sqrt(3))
    (psi = 0, Eq. 13), the derivative of `mc_constants` at the trial's Lode angle through
    Eq. (17)-(18): here by central differences."""
    from psph.kernels.plasticity import softened

    phi_r, c_r, eta, eps0 = math.radians(20.0), 1e3, 30.0, 0.01
    trial = (-60e3, -90e3, -200e3, 20e3, -10e3, 5e3)
    s = np.array(trial)
    d = s.copy()
    d[:3] -= s[:3].mean()
    j2 = 0.5 * np.sum(d[:3] ** 2) + np.sum(d[3:] ** 2)
    st, ct = lode_sin_cos(*d, j2)
    i1 = s[:3].sum()

    def f_at(eps):
        phi, c, _ = softened(eps, PHI, phi_r, C, c_r, 0.0, eta, 0.0)
        xi, kap = mc_constants(phi, c, st, ct)
        return xi * i1 + math.sqrt(j2) - kap

    step = 1e-7
    dfde = (f_at(eps0 + step) - f_at(eps0 - step)) / (2 * step)
    out = ret(trial, eps=eps0, phi_r=phi_r, c_r=c_r, eta=eta)
    assert f_at(eps0) > 1e3 and dfde > 0.0
    assert out[6] == pytest.approx(f_at(eps0) / (G - dfde / math.sqrt(3)), rel=1e-6)


def test_the_default_is_the_plane_strain_cone():
    """The default return is Eq. (16)'s cone (flag off; its bits against the commit
    before: tests/test_plasticity.py, `..._paper_law_bit_for_bit`); the Mohr-Coulomb
    cone is the stronger in triaxial compression."""
    trial = (-60e3, -60e3, -200e3, 0.0, 0.0, 0.0)  # triaxial compression, outside both
    plane = ret(trial, mc=False)
    mc = ret(trial)
    assert plane == dp_return_3d(*trial, 0.0, K, G, DruckerPrager(PHI, PHI, C, C, 0.0, 0.0, 0.0))
    q = lambda s: math.sqrt(0.5 * ((s[0] - s[1]) ** 2 + (s[1] - s[2]) ** 2  # noqa: E731
                                   + (s[2] - s[0]) ** 2))
    assert q(mc) > 1.3 * q(plane)


def test_surface_reaches_the_material_table():
    from psph.config.load import load_scene
    from psph.kernels.update import MAT_MOHR_COULOMB
    from psph.physics.material import material_table

    assert material_table(load_scene("collapse_dry"))[0, MAT_MOHR_COULOMB] == 0.0
    sets = ['material.plasticity.surface="mohr_coulomb"']
    assert material_table(load_scene("collapse_dry", sets))[0, MAT_MOHR_COULOMB] == 1.0

"""The dissipated plastic work `plastic_work` (issue 17, item 2): one particle driven
through `update.advance` with a prescribed velocity gradient accumulates sigma : d eps_p
(J/m^3) as the analytic value of its strain path; an elastic material accumulates none; a
checkpoint written before the field existed restarts with zeros."""

import math

import numpy as np
import pytest

from psph.kernels.bundles import StepParams, SurfaceLoads, UpdateFields
from psph.kernels.sum_columns import GV, M_XX, M_YY, NSUMS
from psph.kernels.update import SCHEME_NONE, advance
from psph.physics.material import material_row

E, NU = 2.6e7, 0.3
SHEAR = E / (2 * (1 + NU))
LAM = E * NU / ((1 + NU) * (1 - 2 * NU))
BULK = LAM + 2 * SHEAR / 3
SIGMA0 = -5e4  # isotropic effective stress (Pa)


def _drive(grad: np.ndarray, steps: int, dt: float, dp: np.ndarray | None) -> dict:
    """One particle whose corrected velocity gradient is `grad` (L[a, b] = dv_a/dx_b) for
    `steps` steps of dt; returns the stress after each step, eps_p and plastic_work."""
    sums = np.zeros((1, NSUMS))
    sums[0, M_XX] = sums[0, M_YY] = 1.0  # identity moment matrix: no correction
    sums[0, GV] = grad.ravel()  # GV_XX, GV_XY, GV_YX, GV_YY: row-major
    z = np.zeros
    x, u, v, acc = z((1, 2)), z((1, 2)), z((1, 2)), z((1, 2))
    stress = np.array([[SIGMA0, SIGMA0, SIGMA0, 0.0]])
    one = np.ones(1)
    eps_p, work = z(1), z(1)
    mat = material_row(LAM, SHEAR, 2650.0, dp=dp)
    path = [stress[0].copy()]
    for k in range(steps):
        fields = UpdateFields(x, u, v, stress, z(1), z(1), 0.4 * one, 0.4 * one, one, one,
                              2000.0 * one, z(1), acc, np.full(1, np.inf), z(1), eps_p, work)
        par = StepParams(dt, k * dt, 2e9, 9810.0, 1000.0, 0.0, 0.0, 0.0, SCHEME_NONE, 0.0,
                         False, True, dp is not None, 0, True).typed()
        bad = advance(1, sums, fields, SurfaceLoads(np.full(1, -1.0), z((1, 2)), z(1)), mat,
                      eps_p, np.array([-1e3, -1e3, 1e3, 1e3]), par)
        assert bad < 0
        path.append(stress[0].copy())
    return {"stress": np.array(path), "eps_p": eps_p[0], "work": work[0]}


def test_constant_stress_yielding_in_pure_shear_dissipates_tau_times_plastic_shear():
    """phi = psi = 0, no softening: sqrt(J2) = |tau| yields at c. Pure shear (no spin)
    at rate gamma_dot: tau = G gamma until c, then constant; the work is
    c (gamma - c / G), with gamma = 2 eps_xy the engineering shear strain."""
    c = 2e4
    dp = np.array([0.0, 0.0, c, c, 0.0, 0.0, 0.0])
    gamma_dot, dt, steps = 1e-2, 1e-3, 300  # gamma = 3e-3, yield at 1.0e-3
    grad = np.array([[0.0, 0.5 * gamma_dot], [0.5 * gamma_dot, 0.0]])
    r = _drive(grad, steps, dt, dp)
    assert r["stress"][-1, 3] == pytest.approx(c, rel=1e-12)
    gamma = gamma_dot * dt * steps
    assert r["work"] == pytest.approx(c * (gamma - c / SHEAR), rel=2e-3)
    assert r["eps_p"] == pytest.approx((gamma - c / SHEAR) / math.sqrt(3), rel=2e-3)


def test_frictional_dilatant_work_equals_stress_times_plastic_strain_of_each_step():
    """phi = 30, psi = 10 deg, softening cohesion, in shear with compression: the work of
    each step equals sigma : (d eps - C^-1 d sigma) (the plastic part of the step's strain,
    plane strain, isotropic compliance), summed (the radial return keeps the deviator's
    direction, so d_lambda dg/dsigma at the returned stress is the step's plastic
    strain; the scaling back is not counted, a second-order difference)."""
    dp = np.array([math.radians(30), math.radians(25), 1e4, 2e3, math.radians(10), 5.0,
                   3.0])
    dt, steps = 1e-3, 400
    grad = np.array([[-2e-3, 1.5e-2], [1.5e-2, -1e-3]])  # no spin: no Jaumann terms
    r = _drive(grad, steps, dt, dp)
    d = 0.5 * (grad + grad.T) * dt
    d_eps = np.array([d[0, 0], d[1, 1], 0.0, d[0, 1]])  # xx, yy, zz, xy (tensor)
    s = r["stress"]
    ds = np.diff(s, axis=0)
    mean = ds[:, :3].sum(1) / 3
    d_el = np.empty_like(ds)
    d_el[:, :3] = (ds[:, :3] - mean[:, None]) / (2 * SHEAR) + (mean / (3 * BULK))[:, None]
    d_el[:, 3] = ds[:, 3] / (2 * SHEAR)
    d_pl = d_eps[None, :] - d_el
    # tiny negative terms are the roundoff of elastic steps
    per_step = (s[1:, :3] * d_pl[:, :3]).sum(1) + 2 * s[1:, 3] * d_pl[:, 3]
    assert r["eps_p"] > 1e-3  # it yielded and softened
    assert r["work"] > 0.0
    # 2e-6 apart: the scaling back onto the softened surface (`dp_return`) adds a
    # plastic strain of second order that d_lambda does not count
    assert r["work"] == pytest.approx(per_step.sum(), rel=1e-5)


def test_elastic_material_or_stress_below_yield_dissipates_nothing():
    grad = np.array([[0.0, 1e-2], [0.0, 0.0]])
    assert _drive(grad, 300, 1e-3, None)["work"] == 0.0
    dp = np.array([0.0, 0.0, 1e6, 1e6, 0.0, 0.0, 0.0])  # far from yield
    r = _drive(grad, 300, 1e-3, dp)
    assert r["work"] == 0.0 and r["eps_p"] == 0.0

"""Element tests: a homogeneously deformed saturated soil block, SPH against a no-SPH ODE.

A square lattice block (11 x 11 particles, dx = 0.1 m, h = 1.2 dx, V = dx^2, n0 = 0.4),
all particles at the same state: isotropic effective stress sigma'0 (tension positive),
excess pore pressure p0 = 0 (compression positive), eps_p = 0. Every step every particle
gets the linear velocity v = L (x - x_c), so every particle whose kernel support lies in
the block sees an exactly homogeneous deformation; the centre particle is compared.

Two plane-strain paths (eps_zz = 0), with the volumetric rate e_v servo-controlled so that
the total mean stress (sigma'xx + sigma'yy + sigma'zz)/3 - p of the centre particle stays at
its initial value:

- compression: L = diag(r + e_v, -r) (axial strain r t along y);
- simple shear: L = [[e_v/2, g], [0, e_v/2]] (shear strain g t).

In elasticity this keeps e_v = 0 and p = 0 undrained; all excess p comes from the plastic
volume change of the Drucker-Prager flow rule (dilatancy psi, Eq. 15).

`sph_element` runs the project's kernels: `interactions.pair_sums` (Eq. 22 sums) and
`update.advance` (stress by the Jaumann rate Eq. (11) with the return of Eq. (13)-(19),
porosity Eq. (24), explicit pore pressure Eq. (25)), with k tiny, no gravity, no damping,
`kicked=True` (advance only moves x with the prescribed v). `reference_element`
integrates the same constitutive law as ODEs of the centre particle, with the same forward
Euler order as `advance`: the elastic predictor with the Jaumann rate of Eq. (11) (spin
terms included) and `plasticity.dp_return`; dn/dt = (1 - n) e_v (Eq. 24 for a homogeneous
v); dp/dt = -(K_l/n) e_v (Eq. 25 without flow); p = 0 drained. Both use the same secant
servo (`servo_step`).

By default `advance` takes the shear rate and spin of the stress rate from the plain
(uncorrected) kernel gradient L M (`correct_strain=False`: the corrected one grows a
zig-zag mode at free surfaces, `update.make_advance`) and the normal rates from the
corrected gradient. On the lattice the moment matrix M of Eq. (22)
is 0.9908 I instead of I (h = 1.2 dx), so in simple shear the shear stress rate is 0.9 %
slow and the SPH p ends up to about 1 % of its peak below the reference.
`reference_element(..., moment=moment_history(sph))` takes the M(t) measured at the
centre and then reproduces SPH to 1e-6: that is the whole difference. With
`correct_strain=True` SPH is the reference to the servo tolerance.

    python -m psph.verify.element [--drained]   # the six cases, reference vs SPH
"""

import argparse
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from psph.kernels.bundles import (
    DruckerPrager,
    PairFields,
    PairParams,
    PairRecord,
    StepParams,
    SurfaceLoads,
    UpdateFields,
    fields_of,
    sorted_cells,
)
from psph.kernels.interactions import pair_sums
from psph.kernels.neighbours import cell_lists
from psph.kernels.plasticity import dp_return
from psph.kernels.sum_columns import MOMENT, NSUMS
from psph.kernels.update import SCHEME_EXPLICIT, advance
from psph.physics.material import ElasticSoil, material_row

PATHS = ("compression", "shear")
DEFAULT_RATE = {"compression": 5e-3, "shear": 1e-2}  # 1/s: 2 % axial, 4 % shear at 4 s


@dataclass(frozen=True)
class ElementParams:
    """Material (Table 1 of the paper, n0 = 0.4), initial state and loading."""

    E: float = 20e6
    nu: float = 0.33
    K_l: float = 1e9
    rho_s: float = 2650.0
    rho_l: float = 1000.0
    g: float = 9.81
    porosity: float = 0.4
    perm: float = 1e-12  # m/s: Darcy flow negligible (undrained)
    phi_deg: float = 25.0
    c: float = 5e3
    phi_r_deg: float | None = None  # None: = phi (no softening)
    c_r: float | None = None  # None: = c
    eta: float = 0.0
    s_f: float = 0.0
    tension: float = math.inf  # tension cut-off of sigma'_m (Pa); inf: the apex (Eq. 14)
    sigma0: float = -100e3  # isotropic effective stress (Pa), tension positive
    rate: float | None = None  # r or shear rate (1/s); None: DEFAULT_RATE[path]
    dt: float = 0.01
    steps: int = 400
    checkpoints: int = 10
    dx: float = 0.1
    h_factor: float = 1.2
    side: int = 11  # particles per side (odd: a centre particle)

    @property
    def soil(self) -> ElasticSoil:
        """The elastic constants (shear, lam, ...) as the solver derives them."""
        return ElasticSoil(E=self.E, nu=self.nu, rho_s=self.rho_s, rho_l=self.rho_l,
                           K_l=self.K_l, gamma_l=self.rho_l * self.g,
                           porosity=self.porosity, conductivity=self.perm)

    def plasticity(self, psi_deg: float) -> np.ndarray:
        """(phi_p, phi_r, c_p, c_r, psi0, eta, s_f) as in `material.plasticity_parameters`."""
        phi_r = self.phi_deg if self.phi_r_deg is None else self.phi_r_deg
        c_r = self.c if self.c_r is None else self.c_r
        return np.array([math.radians(self.phi_deg), math.radians(phi_r), self.c, c_r,
                         math.radians(psi_deg), self.eta, self.s_f])


def velocity_gradient(path: str, rate: float, e_v: float) -> np.ndarray:
    """L[a, b] = dv_a/dx_b of the path with volumetric rate e_v = trace L."""
    if path == "compression":
        return np.array([[rate + e_v, 0.0], [0.0, -rate]])
    if path == "shear":
        return np.array([[0.5 * e_v, rate], [0.0, 0.5 * e_v]])
    raise ValueError(f"path must be one of {PATHS}, not {path!r}")


def mean_total(stress: np.ndarray, p: float) -> float:
    """(sigma'xx + sigma'yy + sigma'zz)/3 - p (Pa), Eq. (2)."""
    return float(stress[0] + stress[1] + stress[2]) / 3.0 - float(p)


def sqrt_j2(stress: np.ndarray) -> float | np.ndarray:
    """sqrt(J2) of the effective stress xx, yy, zz, xy (Pa): a float for one row, an
    array for rows (N, 4+)."""
    s = np.asarray(stress, dtype=float)
    m = (s[..., 0] + s[..., 1] + s[..., 2]) / 3.0
    j2 = 0.5 * ((s[..., 0] - m) ** 2 + (s[..., 1] - m) ** 2 + (s[..., 2] - m) ** 2) \
        + s[..., 3] ** 2
    return math.sqrt(float(j2)) if s.ndim == 1 else np.sqrt(j2)


def jaumann_elastic(stress: np.ndarray, grad: np.ndarray, lam: float, shear: float,
                    dt: float) -> np.ndarray:
    """Elastic predictor of Eq. (11), plane strain, exactly as in `update.advance`."""
    (l00, l01), (l10, l11) = grad
    e01 = 0.5 * (l01 + l10)
    w = 0.5 * (l01 - l10)
    sxx, syy, szz, sxy = stress
    return np.array([
        sxx + dt * ((lam + 2 * shear) * l00 + lam * l11 + 2 * w * sxy),
        syy + dt * (lam * l00 + (lam + 2 * shear) * l11 - 2 * w * sxy),
        szz + dt * lam * (l00 + l11),
        sxy + dt * (2 * shear * e01 + w * (syy - sxx)),
    ])


def plain_gradient(grad: np.ndarray, moment: np.ndarray) -> np.ndarray:
    """The velocity gradient that `advance` gives the stress rate with
    correct_strain=False: the off-diagonal (shear, spin) of the plain kernel gradient L M
    (M the moment matrix of Eq. 22), the diagonal (normal rates, so div v of Eq. 24-25)
    of the corrected one, L."""
    g = grad @ moment
    g[0, 0] = grad[0, 0]
    g[1, 1] = grad[1, 1]
    return g


def servo_step(evaluate: Callable[[float], tuple[object, float]], target: float,
               guess: float, delta: float, tol: float,
               max_evals: int = 8) -> tuple[float, object, int]:
    """Secant iteration on f(e_v) = evaluate(e_v)[1] - target (piecewise linear in e_v).

    evaluate(e_v) -> (state after the step, mean total stress after it), on copies.
    Returns (e_v, that state, evaluations used)."""
    e0 = guess
    s0, m0 = evaluate(e0)
    f0 = m0 - target
    if abs(f0) <= tol:
        return e0, s0, 1
    e1 = e0 + delta
    best = (abs(f0), e0, s0)
    evals = 1
    while evals < max_evals:
        s1, m1 = evaluate(e1)
        evals += 1
        f1 = m1 - target
        if abs(f1) < best[0]:
            best = (abs(f1), e1, s1)
        if abs(f1) <= tol or f1 == f0:
            break
        e0, f0, e1 = e1, f1, e1 - f1 * (e1 - e0) / (f1 - f0)
    return best[1], best[2], evals


def _checkpoint_steps(par: ElementParams) -> np.ndarray:
    return np.round(np.arange(1, par.checkpoints + 1) * par.steps / par.checkpoints).astype(int)


def _record(out: dict, t: float, rate: float, stress: np.ndarray, p: float, n: float,
            par: ElementParams) -> None:
    out["time"].append(t)
    out["strain"].append(rate * t)
    out["p"].append(float(p))
    out["mean_eff"].append(float(stress[0] + stress[1] + stress[2]) / 3.0)
    out["sqrt_j2"].append(sqrt_j2(stress))
    # Eq. (24) for a homogeneous v: d(1 - n)/(1 - n) = -e_v dt
    out["eps_v"].append(math.log((1.0 - par.porosity) / (1.0 - n)))


def _new_output() -> dict:
    return {k: [] for k in ("time", "strain", "p", "mean_eff", "sqrt_j2", "eps_v")}


Moment = np.ndarray | Callable[[float], np.ndarray] | None


def reference_element(path: str, psi_deg: float, drained: bool, moment: Moment = None,
                      **params) -> dict[str, np.ndarray]:
    """The element as ODEs of one material point (no SPH).

    moment: optional 2x2 matrix M, or M(t); the stress rate then takes
    `plain_gradient(L, M)` instead of L, as `advance` does with correct_strain=False
    (see `moment_history`). Porosity and p (Eq. 24-25) keep L, as in `advance`.
    Returns arrays over the checkpoints (the first is the initial state): time (s),
    strain (axial r t or shear g t), p (Pa), mean_eff (sigma'_m, Pa), sqrt_j2 (Pa),
    eps_v (volumetric strain from n, Eq. 24)."""
    par = replace(ElementParams(), **params)
    rate = DEFAULT_RATE[path] if par.rate is None else par.rate
    dp = par.plasticity(psi_deg)
    if callable(moment):
        moment_at = moment
    else:
        fixed = np.eye(2) if moment is None else np.asarray(moment, float)

        def moment_at(t: float) -> np.ndarray:
            return fixed
    state = (np.full(4, par.sigma0) * np.array([1, 1, 1, 0]), 0.0, par.porosity, 0.0)
    target = mean_total(state[0], state[3])
    out = _new_output()
    _record(out, 0.0, rate, state[0], state[3], state[2], par)
    marks = set(_checkpoint_steps(par).tolist())
    e_v = 0.0

    def step(st, e, mom):
        stress, eps_p, n, p = st
        grad = velocity_gradient(path, rate, e)
        trial = jaumann_elastic(stress, plain_gradient(grad, mom), par.soil.lam, par.soil.shear,
                                par.dt)
        r = dp_return(*trial, eps_p, par.soil.lam + 2 * par.soil.shear / 3, par.soil.shear,
                      DruckerPrager(*dp, par.tension))
        div = grad[0, 0] + grad[1, 1]
        p_new = 0.0 if drained else p - par.dt * par.K_l / n * div
        new = (np.array(r[:4]), eps_p + r[5], n + par.dt * (1 - n) * div, p_new)
        return new, mean_total(new[0], new[3])

    for k in range(1, par.steps + 1):
        mom = moment_at((k - 1) * par.dt)
        e_v, state, _ = servo_step(lambda e, st=state, m=mom: step(st, e, m), target, e_v,
                                   1e-4 * rate, 1e-9 * abs(target))
        if k in marks:
            _record(out, k * par.dt, rate, state[0], state[3], state[2], par)
    return {k: np.array(v) for k, v in out.items()}


def _lattice(par: ElementParams) -> tuple[np.ndarray, int]:
    g = (np.arange(par.side) - par.side // 2) * par.dx
    x = np.array(np.meshgrid(g, g, indexing="xy")).reshape(2, -1).T.copy()
    centre = int(np.argmin(np.hypot(x[:, 0], x[:, 1])))
    return x, centre


class _SphBlock:
    """Particle arrays of the block and one `pair_sums` + `advance` step on copies."""

    def __init__(self, par: ElementParams, path: str, rate: float, psi_deg: float,
                 drained: bool, correct_strain: bool):
        self.par, self.path, self.rate = par, path, rate
        self.correct_strain = correct_strain
        self.dp = par.plasticity(psi_deg)
        self.mat = material_row(par.soil.lam, par.soil.shear, par.rho_s, par.perm,
                                dp=self.dp, tension=par.tension)
        self.h = par.h_factor * par.dx
        x, self.centre = _lattice(par)
        n = self.n = len(x)
        rho = (1 - par.porosity) * par.rho_s + par.porosity * par.rho_l
        stress = np.zeros((n, 4))
        stress[:, :3] = par.sigma0
        self.state = {"x": x, "u": np.zeros((n, 2)), "stress": stress, "p": np.zeros(n),
                      "p_prev": np.zeros(n), "poro": np.full(n, par.porosity),
                      "vol": np.full(n, par.dx**2), "rho": np.full(n, rho),
                      "perm": np.full(n, par.perm), "acc": np.zeros((n, 2)),
                      "eps_p": np.zeros(n), "plastic_work": np.zeros(n)}
        self.poro0 = np.full(n, par.porosity)
        self.vol0 = np.full(n, par.dx**2)
        self.drained_from = np.full(n, 0.0 if drained else np.inf)
        self.load_index = np.full(n, -1, np.int64)
        self.material = np.zeros(n)
        self.traction = np.zeros((n, 2))
        self.load_value = np.zeros(1)
        self.box = np.array([-1e3, -1e3, 1e3, 1e3])
        self.sums = np.zeros((n, NSUMS))
        self.t = 0.0

    def evaluate(self, cells, e_v: float) -> tuple[dict, float]:
        """The state after one step with volumetric rate e_v, and the centre's mean total
        stress; self.state is not touched."""
        par, st = self.par, {k: a.copy() for k, a in self.state.items()}
        grad = velocity_gradient(self.path, self.rate, e_v)
        xc = st["x"][self.centre]
        v = (st["x"] - xc) @ grad.T
        z = np.zeros
        pair_sums(self.n, self.n, self.n,
                  fields_of(PairFields, st, v=v, v_slip=v, astress=z((self.n, 3))),
                  sorted_cells(*cells, st["x"]), PairParams(self.h).typed(), self.sums,
                  PairRecord(z((0, 2), np.int64), z((0, 2))))
        fields = fields_of(UpdateFields, st, v=v, poro0=self.poro0, vol0=self.vol0,
                           drained_from=self.drained_from, material=self.material)
        par_step = StepParams(par.dt, self.t, par.K_l, par.rho_l * par.g, par.rho_l, 0.0, 0.0,
                              0.0, SCHEME_EXPLICIT, 0.0, False, self.correct_strain, True, 0,
                              True).typed()
        bad = advance(self.n, self.sums, fields,
                      SurfaceLoads(self.load_index, self.traction, self.load_value), self.mat,
                      st["eps_p"], self.box, par_step)
        if bad >= 0:
            raise FloatingPointError(f"advance flagged particle {bad} at t = {self.t:g} s")
        c = self.centre
        return st, mean_total(st["stress"][c], st["p"][c])

    def moment(self) -> np.ndarray:
        """Moment matrix M of Eq. (22) at the centre at the current positions: the plain
        kernel gradient of a linear field v = L x is L M there."""
        self.evaluate(cell_lists(self.state["x"], self.h), 0.0)  # fills self.sums
        return self.sums[self.centre, MOMENT].reshape(2, 2).copy()


def sph_element(path: str, psi_deg: float, drained: bool, correct_strain: bool = False,
                **params) -> dict[str, np.ndarray]:
    """The element run through `pair_sums` and `advance`; same return as
    `reference_element` (centre particle), plus `moment` (2x2 plain-gradient moment
    matrix of the centre at each checkpoint)."""
    par = replace(ElementParams(), **params)
    rate = DEFAULT_RATE[path] if par.rate is None else par.rate
    blk = _SphBlock(par, path, rate, psi_deg, drained, correct_strain)
    c = blk.centre
    target = mean_total(blk.state["stress"][c], blk.state["p"][c])
    out = _new_output()
    _record(out, 0.0, rate, blk.state["stress"][c], 0.0, par.porosity, par)
    out["moment"] = [blk.moment()]
    marks = set(_checkpoint_steps(par).tolist())
    e_v = 0.0
    for k in range(1, par.steps + 1):
        cells = cell_lists(blk.state["x"], blk.h)
        e_v, blk.state, _ = servo_step(lambda e, cl=cells: blk.evaluate(cl, e), target, e_v,
                                       1e-4 * rate, 1e-9 * abs(target))
        blk.t = k * par.dt
        if k in marks:
            st = blk.state
            _record(out, blk.t, rate, st["stress"][c], st["p"][c], st["poro"][c], par)
            out["moment"].append(blk.moment())
    return {k: np.array(v) for k, v in out.items()}


def moment_history(sph: dict[str, np.ndarray]) -> Callable[[float], np.ndarray]:
    """M(t) of the centre, interpolated between the checkpoints of an `sph_element` run,
    for `reference_element(..., moment=...)`."""
    t = sph["time"]
    m = sph["moment"].reshape(len(t), 4)

    def at(time: float) -> np.ndarray:
        return np.array([np.interp(time, t, m[:, j]) for j in range(4)]).reshape(2, 2)

    return at


def relative_error(a: np.ndarray, b: np.ndarray, scale: float) -> float:
    """max |a - b| / scale over the checkpoints."""
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b)))) / scale


def error_scale(ref: dict[str, np.ndarray], key: str, **params) -> float:
    """Scale of the errors of `key`: the peak |reference|; where the reference stays
    ~ 0 (psi = 0: below 1 % of the natural scale), the natural scale itself: |sigma'0| for
    stresses and p, |sigma'0| / K (the elastic volumetric strain of sigma'0) for eps_v."""
    par = replace(ElementParams(), **params)
    natural = abs(par.sigma0)
    if key == "eps_v":
        natural /= par.soil.lam + 2 * par.soil.shear / 3
    peak = float(np.max(np.abs(ref[key])))
    return peak if peak > 0.01 * natural else natural


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m psph.verify.element",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--drained", action="store_true", help="the drained cases (p = 0)")
    args = ap.parse_args(argv)
    key, unit, fac = ("eps_v", "1e-3", 1e3) if args.drained else ("p", "kPa", 1e-3)
    print(f"final {key} ({unit}) of the centre particle; err: max over the checkpoints, % of"
          f" the peak |reference| (psi = 0: of |sigma'0|{'/K' if args.drained else ''})")
    print(f"{'path':12s} {'psi':>5s} {'reference':>10s} {'sph':>10s} {'err %':>6s}"
          f" {'sph corr.':>10s} {'err %':>8s}")
    for path in PATHS:
        for psi in (-5.0, 0.0, 5.0):
            ref = reference_element(path, psi, args.drained)
            plain = sph_element(path, psi, args.drained)
            corr = sph_element(path, psi, args.drained, correct_strain=True)
            scale = error_scale(ref, key)
            e1 = 100 * relative_error(plain[key], ref[key], scale)
            e2 = 100 * relative_error(corr[key], ref[key], scale)
            print(f"{path:12s} {psi:5.1f} {ref[key][-1] * fac:10.3f} {plain[key][-1] * fac:10.3f}"
                  f" {e1:6.2f} {corr[key][-1] * fac:10.3f} {e2:8.1e}")
    print("sph: correct_strain=False (the scenes' default: plain kernel gradient, moment"
          " matrix 0.991 I on the lattice); sph corr.: correct_strain=True (Eq. 22)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

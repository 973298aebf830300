"""A one-dimensional softening shear band: the energy it dissipates at two particle
spacings, with and without the non-local regularisation.

A layer 0 <= y <= H in simple shear (plane strain): the bottom is fixed, the top moves
along x at a constant speed. The layer's particles sit at y_k = (k + 1/2) dy; each carries
the shear stress tau (effective stress isotropic, sigma0, plus tau = sigma'_xy), the local
equivalent plastic strain eps_p and the Drucker-Prager law of `plasticity.dp_return`
(Eq. 13-19) with phi = psi = 0: sqrt(J2) = |tau| yields at the cohesion c(eps), Eq. (18),
softening from c_p to c_r = 0 at rate eta. The cohesion of the layer has a smooth dip of
1 % at mid-height (the same function of y at every dy), where the band forms.

Equilibrium d tau / dy = rho dv/dt is integrated explicitly on a staggered line (nodes
between particles carry the velocity; a mass-proportional damping c_d, small enough that
it moves tau by < 1 %); each step every particle takes the elastic trial
tau + G dgamma and `dp_return` at the softening strain: its own eps_p (local, today's
law), or the over-non-local eps_hat of `kernels/nonlocal_strain.py` computed with the
solver's kernel on a lattice strip (the layer's column repeated along x so that the
support is full: the 2D weights of a run). The dissipated plastic work per unit band
area (per metre along the band, plane strain) is

    G_d = sum_k dy sum_steps d_lambda_k (xi_psi I1 + sqrt(J2))_k  (J/m^2),

sigma : d eps_p with d eps_p = d_lambda dg/dsigma of Eq. (15), d_lambda of Eq. (13).
Local: the band is one particle row and G_d follows dy. Non-local: G_d is a material
property (set by l_c).

    python bench/studies/softening_band.py            # the table (local and three l_c, m)
    python bench/studies/softening_band.py --quick    # the local law at the coarser dy

Prints the table, writes <out>/softening_band.json. `tests/test_regularisation.py` checks
that G_d is objective with the regularisation only.
"""

import argparse
import json
import math
import sys
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numba as nb
import numpy as np

from psph.kernels.bundles import CellList, DruckerPrager, NonlocalFields
from psph.kernels.neighbours import cell_lists_indexed
from psph.kernels.nonlocal_strain import nonlocal_strain, rings_for
from psph.kernels.plasticity import dp_constants, dp_return


@dataclass(frozen=True)
class BandParams:
    """Layer, material (Pa, kg/m^3, m) and loading."""

    height: float = 0.3  # H (m)
    E: float = 26e6
    nu: float = 0.3
    rho: float = 2000.0
    sigma0: float = -50e3  # isotropic effective stress (Pa)
    c_p: float = 20e3  # peak cohesion (Pa); phi = psi = 0
    eta: float = 20.0  # softening rate of Eq. (18), c_r = 0
    dip: float = 0.01  # relative cohesion dip at mid-height
    dip_width: float = 0.02  # its Gaussian width (m)
    speed: float = 0.05  # top velocity (m/s)
    slip: float = 0.025  # top displacement at the end (m)
    damping: float = 20.0  # c_d (1/s)
    courant: float = 0.8  # dt = courant dy / c_s


@dataclass(frozen=True)
class BandResult:
    dissipated: float  # G_d (J/m^2)
    band_width: float  # width where eps_p > half its peak (m)
    peak_tau: float  # highest shear stress (Pa)
    final_tau: float  # shear stress at the end (Pa)


@nb.njit(cache=True)
def _run(n, dy, steps, dt, speed, rho, damping, bulk, shear, sigma0, c_p, dip, dip_width,
         eta, length, weight, x, vol, material, cell_of, cell_start, order, ncell, rings,
         n_real, state):
    """The time loop; state columns: 0 tau, 1 eps_p, 2 eps_hat, 3 v at node k (top node
    n extra row), 4 G_d density per particle. Returns (G_d, peak tau)."""
    lengths = np.array([length])
    weights = np.array([weight])
    eps_all = np.zeros(n_real)
    plastic_cell = np.zeros(ncell[0] * ncell[1], np.int8)
    no_walls = np.zeros(0, np.int64)  # the band's ends are its loads, not walls
    no_pos = np.zeros(0)
    height = n * dy
    peak = 0.0
    for _ in range(steps):
        # softening strain
        if length > 0.0:
            for j in range(n_real):
                eps_all[j] = state[j % n, 1]
            nonlocal_strain(n, n_real, NonlocalFields(x, vol, eps_all, material), lengths,
                            weights, CellList(cell_of, cell_start, order, ncell), rings,
                            plastic_cell, no_walls, no_pos, state[:, 2])
        else:
            for k in range(n):
                state[k, 2] = state[k, 1]
        # stress update of every particle from the node velocities (k below, k + 1 above)
        for k in range(n):
            v_lo = state[k, 3]
            v_hi = speed if k == n - 1 else state[k + 1, 3]
            tau = state[k, 0] + dt * shear * (v_hi - v_lo) / dy
            yk = (k + 0.5) * dy
            ck = c_p * (1.0 - dip * math.exp(-((yk - 0.5 * height) / dip_width) ** 2))
            r = dp_return(sigma0, sigma0, sigma0, tau, state[k, 2], bulk, shear,
                          DruckerPrager(0.0, 0.0, ck, 0.0, 0.0, eta, 0.0, math.inf, False))
            state[k, 0] = r[3]
            state[k, 1] += r[5]
            i1 = r[0] + r[1] + r[2]
            m = i1 / 3.0
            j2 = 0.5 * ((r[0] - m) ** 2 + (r[1] - m) ** 2 + (r[2] - m) ** 2) + r[3] * r[3]
            xi_psi = dp_constants(0.0, 0.0)[0]
            state[k, 4] += dy * r[4] * (xi_psi * i1 + math.sqrt(j2))
            peak = max(peak, r[3])
        # nodes 1..n-1 between particles k - 1 and k; node 0 fixed, top node moves
        for k in range(1, n):
            a = (state[k, 0] - state[k - 1, 0]) / (rho * dy) - damping * state[k, 3]
            state[k, 3] += dt * a
    return state[:n, 4].sum(), peak


def softening_band(dy: float, length: float = 0.0, weight: float = 2.0,
                   **params) -> BandResult:
    """The layer at spacing dy; length = l_c of the regularisation (0: local law),
    weight = its m."""
    par = replace(BandParams(), **params)
    n = int(round(par.height / dy))
    dy = par.height / n
    shear = par.E / (2 * (1 + par.nu))
    bulk = par.E / (3 * (1 - 2 * par.nu))
    c_s = math.sqrt(shear / par.rho)
    dt = par.courant * dy / c_s
    steps = int(math.ceil(par.slip / par.speed / dt))
    # the strip: column 0 (the layer) first, then the others; h = 0.6 dy for the cells
    ncol = 2 * rings_for(length, dy) + 1 if length > 0.0 else 1
    cols = [0] + [c for c in range(-(ncol // 2), ncol // 2 + 1) if c != 0]
    y = (np.arange(n) + 0.5) * dy
    x = np.concatenate([np.column_stack([np.full(n, c * dy), y]) for c in cols])
    h = max(length, dy)
    cell_of, cell_start, order, ncell = cell_lists_indexed(x, h)
    cs = 2 * h
    state = np.zeros((n + 1, 5))
    g_d, peak = _run(n, dy, steps, dt, par.speed, par.rho, par.damping, bulk, shear,
                     par.sigma0, par.c_p, par.dip, par.dip_width, par.eta, length, weight, x,
                     np.full(len(x), dy * dy), np.zeros(len(x)), cell_of, cell_start, order,
                     ncell, rings_for(length, cs) if length > 0.0 else 1, len(x), state)
    eps = state[:n, 1]
    band = dy * float(np.sum(eps > 0.5 * eps.max())) if eps.max() > 0 else 0.0
    return BandResult(float(g_d), band, float(peak), float(state[n - 1, 0]))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="the local law at dy = 0.01 m only")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "out",
                    help="directory of softening_band.json (default bench/out)")
    args = ap.parse_args(argv)
    laws = ((0.0, 1.0),) if args.quick else ((0.0, 1.0), (0.03, 1.0), (0.03, 2.0), (0.06, 2.0))
    spacings = (0.01,) if args.quick else (0.01, 0.01 / 1.5)
    print(f"{'l_c (m)':>8s} {'m':>4s} {'dy (m)':>8s} {'G_d (J/m2)':>11s} {'band (m)':>9s}"
          f" {'peak tau':>9s} {'end tau':>8s}")
    rows = []
    for length, weight in laws:
        for dy in spacings:
            r = softening_band(dy, length, weight)
            rows.append({"l_c": length, "m": weight, "dy": dy, **asdict(r)})
            print(f"{length:8.3f} {weight:4.1f} {dy:8.4f} {r.dissipated:11.2f}"
                  f" {r.band_width:9.4f} {r.peak_tau:9.0f} {r.final_tau:8.0f}")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "softening_band.json").write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

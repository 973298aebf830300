"""Porosity of a Drucker-Prager run against the flow rule's own bound, Eq. (15) and (19)
of Lian et al. (2023).

A contractive soil (psi < 0) compacts plastically by d eps_v = 3 sqrt(3) xi_psi d eps_p
(plastic potential Eq. 15, multiplier d lambda = sqrt(3) d eps_p, `plasticity.dp_return`),
with psi softening by Eq. (19). Integrated with Eq. (8) (1 - n) = (1 - n0) exp(-eps_v),
the most a particle can compact at its equivalent plastic strain eps_p, drained and
without elastic strain, is

    n_law(eps_p) = 1 - (1 - n0) exp(-3 sqrt(3) int_0^eps_p xi_psi(e) de).

A particle well below n_law has compacted by a strain the constitutive law does not
produce (elastic compaction is about p' / K, 1e-3 for 10 kPa in the Section 4.5 clay):
numerical, e.g. a stress filter that erases the stress resisting the compaction
(`update.porosity_follows_stress_filter`).

`python -m psph.analysis.porosity OUT [OUT ...]` prints, for every snapshot at a multiple of
5 s: the lowest n, the largest deficit n_law - n with its particle, and how many particles
are more than 0.01 below n_law.
"""

import math

import numpy as np

DEFICIT = 0.01  # below n_law by more than this: counted


def porosity_bound(eps_p: np.ndarray, n0: float, psi0_deg: float, s_f: float) -> np.ndarray:
    """n_law(eps_p) of the module docstring (trapezoidal quadrature on 0.001 steps; exact
    for s_f = 0, where the integrand is constant)."""
    eps_p = np.asarray(eps_p, float)
    top = float(eps_p.max()) if eps_p.size else 0.0
    e = np.linspace(0.0, max(top, 1e-9), max(2, int(top / 1e-3) + 2))
    t = np.tan(math.radians(psi0_deg) * np.exp(-s_f * e))
    xi = t / np.sqrt(9.0 + 12.0 * t * t)
    ev = np.concatenate([[0.0], np.cumsum(0.5 * (xi[1:] + xi[:-1]) * np.diff(e))])
    ev *= 3.0 * math.sqrt(3.0)
    return 1.0 - (1.0 - n0) * np.exp(-np.interp(eps_p, e, ev))


def porosity_deficit(snap: dict, n0: float, psi0_deg: float, s_f: float) -> dict:
    """The snapshot's lowest n and its particles' deficit against `porosity_bound`."""
    n = snap["n"]
    deficit = porosity_bound(snap["eps_p"], n0, psi0_deg, s_f) - n
    i = int(np.argmax(deficit))
    return {"time_s": float(snap["time"]), "n_min": float(n.min()),
            "deficit_max": float(deficit[i]), "deficit_id": int(snap["id"][i]),
            "deficit_eps_p": float(snap["eps_p"][i]), "deficit_n": float(n[i]),
            "below_bound": int(np.sum(deficit > DEFICIT))}

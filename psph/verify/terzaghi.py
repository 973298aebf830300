"""Terzaghi's 1D consolidation with a compressible pore fluid (Section 4.1).

Undrained loading (all sides impervious) builds p0 = q (K_l/n) / (K_l/n + M), M the
constrained modulus E(1-nu)/((1+nu)(1-2nu)). Once the column is drained at t_d, the excess
pressure obeys dp/dt = c_v d2p/dz2 with c_v = k / (gamma_l (n/K_l + 1/M)) (mass balance
Eq. 9 with Eq. 5, quasi-static), p = 0 on the drained face(s) and no flux on the others:

  p(z, t) = p0 sum_m 2/M_m sin(M_m z/H_d) exp(-M_m^2 T_v),  M_m = (2m+1) pi/2,
  T_v = c_v (t - t_d) / H_d^2,

with z the distance from the drained face and H_d the drainage length: H for a column
drained at the top (or at the bottom only), H/2 for one drained at both ends (the series
is symmetric about z = H_d, so z is then the depth below the top).

Settlement of the top: s = (q H - int_0^H p dz) / M.
"""

import math
from dataclasses import dataclass

import numpy as np

from psph.physics.material import constrained_modulus


@dataclass(frozen=True)
class Terzaghi:
    height: float  # H (m), drainage length
    load: float  # q (Pa)
    modulus: float  # M, constrained modulus (Pa)
    porosity: float
    bulk_water: float  # K_l (Pa)
    conductivity: float  # k (m/s)
    gamma_l: float  # rho_l g (N/m^3)
    t_drain: float  # s
    drainage: str = "top"  # the drained end(s): "top", "bottom" or "both"

    @property
    def drainage_length(self) -> float:
        """H_d (m): the longest distance pore water travels to a drained face."""
        return 0.5 * self.height if self.drainage == "both" else self.height

    @property
    def p0(self) -> float:
        """Undrained excess pressure after loading (Pa)."""
        kn = self.bulk_water / self.porosity
        return self.load * kn / (kn + self.modulus)

    @property
    def cv(self) -> float:
        """Consolidation coefficient with the fluid storage n/K_l (m^2/s)."""
        return self.conductivity / (
            self.gamma_l * (self.porosity / self.bulk_water + 1.0 / self.modulus))

    def time_of(self, tv: float) -> float:
        return self.t_drain + tv * self.drainage_length**2 / self.cv

    def tv_of(self, t):
        return (np.maximum(np.asarray(t, float) - self.t_drain, 0.0) * self.cv
                / self.drainage_length**2)

    def pressure(self, depth, t, terms: int = 400) -> np.ndarray:
        """Excess pore pressure (Pa) at a depth below the top, at time t >= t_d."""
        depth = np.asarray(depth, float)
        z = (self.height - depth if self.drainage == "bottom" else depth) \
            / self.drainage_length
        tv = float(self.tv_of(t))
        if tv <= 0.0:
            return np.full_like(z, self.p0)
        m = (2 * np.arange(terms) + 1) * math.pi / 2
        series = (2 / m) * np.exp(-(m**2) * tv)
        return self.p0 * np.sin(np.outer(z, m)) @ series

    def settlement(self, t, terms: int = 4000) -> np.ndarray:
        """Downward displacement of the top (m) for t >= t_d (undrained part included).
        The series of the mean pressure converges as 1/terms (relative error ~ 5e-5); the
        mean over the drainage length is the column's (symmetric when drained at both
        ends)."""
        tv = np.atleast_1d(self.tv_of(t))
        m = (2 * np.arange(terms) + 1) * math.pi / 2
        mean_p = self.p0 * (np.exp(-np.outer(tv, m**2)) @ (2 / m**2))  # (1/H) int p dz
        return (self.load - mean_p) * self.height / self.modulus

    def displacement(self, depth: float, t) -> np.ndarray:
        """Downward displacement (m) of the soil at `depth` below the top: the settlement
        less the compression of the layer above it, (q d - int_0^d p dz) / M (16-point
        Gauss-Legendre over the layer). The loaded top row of a particle column sits dx/2
        below the surface, so its settlement is this at depth dx/2."""
        g, wg = np.polynomial.legendre.leggauss(16)
        z = 0.5 * depth * (g + 1.0)
        tt = np.atleast_1d(np.asarray(t, float))
        layer = np.array([0.5 * depth * wg @ self.pressure(z, ti) for ti in tt])
        return self.settlement(tt) - (self.load * depth - layer) / self.modulus


def column_drainage(scene) -> tuple[str, float]:
    """What the reference reads of a scene's sides: ("top", "bottom" or "both", the time
    they drain from). ValueError (the rule `config.rules` reports as exit 2) without a load
    on the top side first, or with the top and the bottom drained from different times."""
    if not scene.loads or scene.loads[0].side != "top":
        raise ValueError("needs a [[loads]] entry on the top side first")
    ends = {name: getattr(scene.boundaries, name).drained_from for name in ("top", "bottom")
            if getattr(scene.boundaries, name).flow == "drained"}
    if len(set(ends.values())) > 1:
        raise ValueError("needs the top and the bottom drained from the same time "
                         f"(boundaries.top/bottom.drained_from: {sorted(ends.values())})")
    drainage = "both" if len(ends) == 2 else next(iter(ends), "top")
    return drainage, min(ends.values(), default=math.inf)


def from_scene(scene) -> Terzaghi:
    """The column of a scene: load on the top, height = the blocks' height, drained at the
    top, the bottom or both (`column_drainage`)."""
    m = scene.material
    modulus = constrained_modulus(m.E, m.nu)
    drainage, t_drain = column_drainage(scene)
    load = scene.loads[0]
    blocks = scene.particles.blocks
    vz = scene.dim - 1  # the vertical axis
    height = max(b.max[vz] for b in blocks) - min(b.min[vz] for b in blocks)
    return Terzaghi(height=height, load=load.pressure, modulus=modulus, porosity=m.porosity,
                    bulk_water=m.K_l, conductivity=m.k, gamma_l=m.rho_l * m.g_ref,
                    t_drain=t_drain, drainage=drainage)

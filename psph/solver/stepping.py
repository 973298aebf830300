"""The time step of each phase and the pressure scheme in force (Eq. 40-42).

Explicit Eq. (25) at min(Eq. 41, Eq. 42, the undrained wave limit); TPI at R x Eq. (42)
capped by Eq. (41) and its own gain bound (`scene.tpi_dt`), after an explicit loading
stage until `pressure.explicit_until`; the projection at the solid limit Eq. (41); a
given `time.dt` overrides the main step. `limits` is what `summary.json` reports.
"""

import math
from dataclasses import dataclass, field

from psph.config.schema import Scene
from psph.kernels.update import SCHEME_EXPLICIT, SCHEME_NONE, SCHEME_PROJECTION, SCHEME_TPI
from psph.physics.limits import (
    fluid_dt_limit,
    solid_dt_limit,
    tpi_dt,
    tpi_gain_dt_limit,
    undrained_dt_limit,
)


@dataclass
class TimeStepping:
    """Time step of each phase (Eq. 40-42) and the scheme in force."""

    dt_main: float
    dt_explicit: float
    scheme_main: int
    explicit_until: float
    limits: dict = field(default_factory=dict)

    def at(self, t: float) -> tuple[float, int]:
        if self.scheme_main == SCHEME_TPI and t < self.explicit_until:
            return self.dt_explicit, SCHEME_EXPLICIT
        return self.dt_main, self.scheme_main


def time_stepping(scene: Scene) -> TimeStepping:
    dt_s = solid_dt_limit(scene)
    scheme = {"none": SCHEME_NONE, "explicit": SCHEME_EXPLICIT, "tpi": SCHEME_TPI,
              "projection": SCHEME_PROJECTION}[scene.pressure.scheme]
    limits = {"dt_solid_eq41": dt_s}
    if scheme == SCHEME_NONE:
        dt_main = dt_s
        dt_exp = dt_s
    else:
        dt_l = fluid_dt_limit(scene)
        dt_u = undrained_dt_limit(scene)
        limits["dt_fluid_eq42"] = dt_l if math.isfinite(dt_l) else None  # k = 0: no flow
        limits["dt_undrained_eq41"] = dt_u
        dt_exp = min(dt_s, dt_l, dt_u)
        if scheme == SCHEME_EXPLICIT:
            dt_main = dt_exp
        elif scheme == SCHEME_PROJECTION:
            dt_main = dt_s  # the solve carries the fluid and the undrained wave
        else:
            limits["dt_tpi_gain"] = tpi_gain_dt_limit(scene)
            dt_main = tpi_dt(scene)
    if scene.time.dt is not None:
        dt_main = scene.time.dt
    return TimeStepping(dt_main, dt_exp, scheme, scene.pressure.explicit_until, limits)

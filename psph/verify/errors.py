"""Error norms against analytical references, computed during a run (reductions go through
the decomposition object, the only holder of the communicator)."""

import numpy as np

from psph.verify import terzaghi


class TerzaghiMonitor:
    """Pore pressure error max|p - p_a| / q at each verification T_v (over all particles)
    and settlement error max|s - s_a| / s_final over T_v in [tv_min, end], s the loaded
    top row's displacement and s_a the reference's at that row's depth dx/2."""

    def __init__(self, scene, slabs):
        self.ref = terzaghi.from_scene(scene)
        self.slabs = slabs
        self.tvs = list(scene.verification.tv)
        self.vz = scene.dim - 1  # the vertical axis
        self.top = max(b.max[self.vz] for b in scene.particles.blocks)
        self.pressure_errors: dict[str, dict] = {}
        self.settlement_error = 0.0
        self.settlement_at_max = None
        self.tv_min = min(self.tvs) if self.tvs else 0.0
        # the settlement is the loaded top row's, dx/2 below the surface
        self.row_depth = 0.5 * scene.particles.dx
        # an undrained start has u = 0 at t_d, where the reference has settled by its
        # undrained part already
        self.s_start = float(self.ref.displacement(self.row_depth, self.ref.t_drain)[0]) \
            if scene.initial.undrained_load else 0.0

    def _tv(self, t: float) -> float:
        return float(self.ref.tv_of(t))

    def snapshot(self, sim) -> None:
        if sim.t < self.ref.t_drain:
            return
        tv = self._tv(sim.t)
        match = [v for v in self.tvs if abs(v - tv) <= 0.02 * v + 1e-12]
        if not match:
            return
        st = sim.store
        n = st.n_owned
        depth = self.top - (st.x[:n, self.vz] - st.u[:n, self.vz])
        pa = self.ref.pressure(depth, sim.t)
        local = float(np.max(np.abs(st.p[:n] - pa))) if n else 0.0
        err = self.slabs.allreduce_max(local) / self.ref.load
        self.pressure_errors[f"{match[0]:g}"] = {"tv_actual": tv, "time_s": sim.t,
                                                 "max_abs_p_error_over_q": err}

    def history(self, sim, row: dict) -> None:
        if sim.t < self.ref.t_drain:
            return
        tv = self._tv(sim.t)
        if tv < self.tv_min * 0.999:
            return
        s_a = float(self.ref.displacement(self.row_depth, sim.t)[0]) - self.s_start
        s_final = self.ref.load * self.ref.height / self.ref.modulus
        e = abs(row["settlement"] - s_a) / s_final
        row["settlement_analytical"] = s_a
        if e > self.settlement_error:
            self.settlement_error = e
            self.settlement_at_max = tv

    def state(self) -> dict:
        """What a checkpoint must carry to continue the error bookkeeping."""
        return {"pressure_errors": self.pressure_errors,
                "settlement_error": self.settlement_error,
                "settlement_at_max": self.settlement_at_max}

    def restore(self, state: dict) -> None:
        self.pressure_errors = dict(state["pressure_errors"])
        self.settlement_error = state["settlement_error"]
        self.settlement_at_max = state["settlement_at_max"]

    def errors(self) -> dict:
        return {
            "reference": "terzaghi",
            "p0_undrained_Pa": self.ref.p0,
            "cv_m2_per_s": self.ref.cv,
            "pressure": self.pressure_errors,
            "max_abs_p_error_over_q": max(
                (v["max_abs_p_error_over_q"] for v in self.pressure_errors.values()),
                default=None),
            "settlement_max_abs_error_over_final": self.settlement_error,
            "settlement_error_worst_tv": self.settlement_at_max,
        }

"""The pressure solve of `pressure.scheme = "projection"` and the residual
monitor of the explicit and TPI pressures: one operator (`kernels/laplacian.py`), its
right-hand side (`kernels/projection.py`), drained planes' images (`kernels/images.py`),
and conjugate gradients with partition-independent inner products (`psph.solver.pcg`, or its
compiled copy `kernels/pcg_serial.py` on one rank: the same bits)."""

import math

import numpy as np

from psph.kernels.bundles import (
    CGWork,
    DotWork,
    FluidParams,
    GhostSources,
    ImageFields,
    ImageWeights,
    ScaledOperator,
    fields_of,
)
from psph.kernels.exact_sum import BLOCK, CHUNK_ROW, CHUNKS, EXPANSION_CAP
from psph.kernels.images import image_weights
from psph.kernels.laplacian import (
    apply_scaled,
    fixed_rhs,
    operator_coefficients,
)
from psph.kernels.pcg_serial import pcg_serial
from psph.kernels.projection import (
    imposed_increments,
    mirror_to_ghosts,
    pressure_correction,
)
from psph.solver.exact_dots import ExactDots
from psph.solver.pcg import PCGResult, PCGWork, pcg
from psph.solver.recycling import RecycledGuess


class PressureSolve:
    """Scratch arrays and statistics of the pressure solve of a `Simulation`."""

    def __init__(self, sim):
        self.sim = sim
        self.stats = {"iterations": 0, "residual": 0.0, "iterations_total": 0,
                      "iterations_max": 0, "not_converged": 0}
        self._a = {}
        self._work = PCGWork()
        self._buf = np.zeros(EXPANSION_CAP)
        self._ones = np.zeros(0)
        self._exact_dots = ExactDots()
        self._terms = np.zeros(BLOCK)
        self._acc = np.zeros(CHUNKS, np.int64)
        self._row = np.zeros(CHUNK_ROW, np.int64)
        self.recycled = RecycledGuess(sim.recycle)
        self._no_r0 = np.zeros(0)

    def _arrays(self, cap: int, n_pairs: int) -> dict:
        a = self._a
        if a.get("cap", 0) < cap:
            dim = self.sim.dim
            a.update(cap=cap, storage=np.zeros(cap), rhs=np.zeros(cap), diag=np.zeros(cap),
                     dp=np.zeros((cap, 1)), imposed=np.zeros((cap, 2)),
                     fixed=np.zeros(cap, np.bool_), dv=np.zeros((cap, dim)),
                     acc=np.zeros((cap, dim)), c_storage=np.zeros(cap))
        if "w" not in a or a["w"].shape[0] < n_pairs:
            m = max(n_pairs, self.sim.pairs.shape[0])
            a.update(w=np.zeros(m), w_diag=np.zeros(m), w_off=np.zeros(m), c_diag=np.zeros(m),
                     c_off=np.zeros(m))
        return a

    def _weights(self, a: dict) -> tuple[np.ndarray, np.ndarray]:
        """The pair weights of the pressure operator (`laplacian.py`) with this step's pairs
        and positions, and the free planes' images (diagonal and off-diagonal weights;
        the images' own part goes into a["storage"], so call after `projection_rhs`)."""
        sim = self.sim
        st = sim.store
        w = a["w"]
        # both parts normalised by the lattice moment, as the Darcy sums and the stress
        # divergence of the step (`Simulation._interactions`)
        k_scale = sim.lattice_norm / sim.soil.gamma_l
        sim.kernels.pair_weights(sim.n_pairs, sim.pairs, sim.pair_g, st.x, st.perm, st.rho,
                                 k_scale, sim.dt * sim.lattice_norm, w)
        if not sim.drainage.has_planes:
            return w, w
        image_weights(st.n_owned, sim.n_pairs, sim.pairs, fields_of(ImageFields, st.arrays),
                      sim.drainage.planes, sim.h, k_scale, sim.dt * sim.lattice_norm, w,
                      ImageWeights(a["w_diag"], a["w_off"], a["storage"]))
        return a["w_diag"], a["w_off"]

    def _system(self, p: np.ndarray, t: float) -> tuple:
        """The linear system of the step about the pressure p (p^n for the solve, p^(n-1)
        for the residual of a step already taken, whose drained rows were imposed at time
        t): storage, right-hand side with the imposed rows' couplings, pair weights and
        the imposed rows. Returns (arrays, w_diag, w_off, fixed, imposed values)."""
        sim = self.sim
        st = sim.store
        s = sim.soil
        n, npairs = st.n_owned, sim.n_pairs
        a = self._arrays(st.cap, npairs)
        imposed, fixed = a["imposed"], a["fixed"]
        fluid = FluidParams(s.rho_l, s.gamma_l, s.K_l, sim.body[0], sim.body[1], sim.b2)
        sim.kernels.projection_rhs(n, sim.sums, p, st.perm, st.vol, st.poro, fluid, sim.dt,
                                   a["storage"], a["rhs"])
        wd, wo = self._weights(a)
        imposed_increments(n, sim.sums, st.drained_from, sim.drainage.layer_clock(t),
                           sim.ponding == 2, p, imposed)
        self.refresh_rows(imposed)
        nt = st.n_total
        np.greater(imposed[:nt, 0], 0.5, out=fixed[:nt])
        value = imposed[:, 1]
        if fixed[:nt].any():  # else the right-hand side has no imposed part
            fixed_rhs(n, npairs, sim.pairs, wd, wo, st.vol, a["storage"], fixed, value,
                      a["rhs"])
        operator_coefficients(n, npairs, sim.pairs, wd, wo, st.vol, a["storage"], a["c_diag"],
                              a["c_off"], a["c_storage"], a["diag"])
        return a, wd, wo, fixed, value

    def residual(self) -> float:
        """How far this step's pressure is from the solve of the projection: the relative
        residual ||b - S dp|| / ||b|| of its linear system (`project`, Eq. 29 with the
        storage n / K_l, the Darcy flux and the velocity correction) at dp = p^(n+1) - p^n
        of the explicit Eq. (25) or TPI Eq. (38) update, with the sums and pairs of the
        step's sweep and the positions after it. Imposed (drained) rows take their
        imposed increment and add nothing. Collective; the same bits on any rank count."""
        sim = self.sim
        st = sim.store
        n, npairs = st.n_owned, sim.n_pairs
        a, wd, wo, fixed, _ = self._system(st.p_prev, sim.t - sim.dt)
        dp = a["dp"]
        d = dp[:, 0]
        np.subtract(st.p[:n], st.p_prev[:n], out=d[:n])
        self.refresh_rows(dp, signed=True)
        res = a["diag"]  # scratch: S dp, then the residual
        apply_scaled(n, npairs, sim.pairs, a["c_diag"], a["c_off"], a["c_storage"], fixed, d, res)
        np.subtract(a["rhs"][:n], res[:n], out=res[:n])
        norm_b = self._dot(a["rhs"], a["rhs"])
        return math.sqrt(self._dot(res, res) / norm_b) if norm_b > 0.0 else 0.0

    def refresh_rows(self, field: np.ndarray, signed: bool = False) -> None:
        """Halo rows from their owners, then wall ghosts from the rows they mirror
        (`signed`: a pressure increment, antisymmetric across a drained wall)."""
        sim = self.sim
        st = sim.store
        sim.slabs.refresh_halo(field)
        if st.n_ghost:
            if not signed and self._ones.shape[0] < st.cap:
                self._ones = np.ones(st.cap)
            sign = sim.ghost_sign if signed else self._ones
            mirror_to_ghosts(st.n_real, st.n_total, sim.ghost_src, sign, field)

    def _dot(self, a: np.ndarray, b: np.ndarray) -> float:
        """Inner product over the owned rows, the same bits on any rank count."""
        return self._dots((a, b))[0]

    def _dots(self, *pairs: tuple[np.ndarray, np.ndarray]) -> list[float]:
        """Inner products over the owned rows in one collective (`exact_dots.ExactDots`:
        integer chunk rows and one integer Allreduce), the same bits on any rank count."""
        return self._exact_dots(self.sim.slabs, self.sim.store.n_owned, *pairs)

    def project(self) -> None:
        """p^(n+1) = p^n + dp from one solve of Eq. (29) (module `psph.kernels.projection`),
        and the velocity correction of dp on the owned rows: of the kicked v* in the
        symplectic step, of v^n in the one-sweep step (`time.integrator = "euler"`, whose
        update kicks after). Collective (the solve's reductions and halo refreshes)."""
        sim = self.sim
        st = sim.store
        n, npairs = st.n_owned, sim.n_pairs
        dt = sim.dt
        a, wd, wo, fixed, value = self._system(st.p, sim.t)
        dp = a["dp"]
        nt = st.n_total
        # warm start: the last two increments extrapolated, 2 (p^n - p^(n-1)) - (p^(n-1) -
        # p^(n-2)) (mean CG iterations 6.7 -> 2.9 on the paper's column at the solid cap,
        # tol 1e-6, the same p); with dp_prev = 0 (the first projection step after an
        # explicit stage, an older checkpoint) the guess is 2 (p^n - p^(n-1)), a guess
        # only; imposed rows at their value
        d = dp[:, 0]
        np.subtract(st.p[:n], st.p_prev[:n], out=d[:n])
        last = st.dp_prev[:n]
        d[:n] *= 2.0
        d[:n] -= last
        np.subtract(st.p[:n], st.p_prev[:n], out=last)
        np.copyto(d[:n], value[:n], where=fixed[:n])

        def apply(q, out):
            apply_scaled(n, npairs, sim.pairs, a["c_diag"], a["c_off"], a["c_storage"], fixed, q,
                         out)

        def refresh(q):
            self.refresh_rows(q.reshape(-1, 1), signed=True)

        recycled = self.recycled
        r0 = None
        if recycled.size:
            free = recycled.free_rows(fixed, n, st.cap)
            basis = (st.recycle_x, st.recycle_sx)
            recycled.start(tuple(sim.drainage.planes[:, 3]) if sim.drainage.has_planes
                           else ())
            recycled.guess(sim, basis, a["rhs"], d, free, apply, refresh)
            r0 = recycled.r0
        self.refresh_rows(dp, signed=True)

        pc = sim.scene.pressure
        if sim.slabs.size == 1:  # the same bits, compiled (kernels/pcg_serial.py)
            wk = self._work
            wk.ensure(st.cap)
            op = ScaledOperator(sim.pairs, a["c_diag"], a["c_off"], a["c_storage"], fixed,
                                a["diag"])
            res = PCGResult(*pcg_serial(n, nt, npairs, op, a["rhs"], d,
                                        GhostSources(sim.ghost_src, sim.ghost_sign),
                                        pc.tolerance, pc.max_iterations,
                                        CGWork(wk.r, wk.u, wk.w, wk.d, wk.sd),
                                        DotWork(self._row, self._terms, self._acc, self._buf),
                                        self._no_r0 if r0 is None else r0))
        else:
            res = pcg(apply, a["diag"], a["rhs"], d, n, self._dots, refresh, pc.tolerance,
                      pc.max_iterations, self._work, r0)
        sv = self.stats
        sv["iterations"], sv["residual"] = res.iterations, res.residual
        sv["iterations_total"] += res.iterations
        sv["iterations_max"] = max(sv["iterations_max"], res.iterations)
        sv["not_converged"] += not res.converged
        if recycled.size:
            recycled.update(sim, basis, d, free, a["rhs"], r0, self._work.r)
        self.refresh_rows(dp, signed=True)
        # after the kick (symplectic step) the correction completes a^n in st.acc; in the
        # one-sweep step `advance` writes a^n there after this, so it is kept aside
        # (`correction_acceleration`) and added back by the update
        acc = st.acc
        if not sim.symplectic:
            acc = a["acc"]
            acc[:n] = 0.0
        pressure_correction(n, npairs, sim.pairs, sim.pair_g, st.vol, st.rho, d, dt,
                            sim.lattice_norm, a["dv"], st.v, acc)
        st.p_prev[:n] = st.p[:n]
        st.p[:n] += d[:n]

    def correction_acceleration(self) -> np.ndarray:
        """The velocity correction's acceleration of the owned rows of this step (the
        one-sweep step: `Simulation._update` adds it to the a^n that `advance` records)."""
        return self._a["acc"][:self.sim.store.n_owned]

"""The state of a run on this rank and its step: the physics stages the scene needs,
each declaring what it reads and writes, assembled once into a pipeline
(`psph/solver/pipeline.py` adds the search and the refreshes those declarations call
for).

Per step: [rebalance every K] -> exchange (migration + halo) -> ghosts (walls) ->
neighbours (cell lists) -> interactions (fused pair sums) -> update (Eq. 22-27, 38-45 of
Lian et al. 2023), with the filters, the kick, the projection and shifting between where
the scene asks for them. Every decision that changes control flow comes from a
collective or from values identical on all ranks (time, step).
"""

import math
import time

import numpy as np

from psph.config.boundaries import plane_walls
from psph.config.schema import Scene
from psph.decomposition.census import Census
from psph.errors import NumericalError
from psph.geometry.lattice import extent, seed
from psph.geometry.shapes import removal_region
from psph.kernels.laplacian import lattice_moment
from psph.kernels.neighbours import pair_cell_span
from psph.kernels.spline import w_cubic, w_cubic_dim
from psph.kernels.sum_columns import sum_layout
from psph.kernels.update import (
    SCHEME_EXPLICIT,
    SCHEME_NONE,
    SCHEME_PROJECTION,
    SCHEME_TPI,
)
from psph.physics.initial import initial_particles
from psph.physics.material import (
    fastest_undrained,
    material_table,
    material_tables_of_trigger,
    plasticity_parameters,
    soil_from_scene,
    stiffest,
)
from psph.physics.softening import nonlocal_softening
from psph.solver.boundary import BoundaryParticles, halo_width, has_boundary_particles
from psph.solver.cells import CellGrid
from psph.solver.drainage import Drainage
from psph.solver.kernel_set import kernels_for
from psph.solver.pipeline import Stage, assemble
from psph.solver.pressure_solve import PressureSolve
from psph.solver.stages import Stages
from psph.solver.stepping import time_stepping
from psph.state.particles import NEIGHBOUR_FIELDS, ParticleStore


class Simulation(Stages):
    """State, pipeline and clock of one run on this rank."""

    def __init__(self, scene: Scene, slabs, particles: dict | None = None, t: float = 0.0,
                 step: int = 0, n_ids: int | None = None, removed: np.ndarray | None = None,
                 removals_done: int = 0, trigger_done: bool = False):
        """`particles`: this rank's rows of every particle field (those of a checkpoint in
        its slab) with the clock (t, step) they belong to; default: the scene's initial
        particles of this rank's slab at t = 0, seeded here (no rank builds them all).
        `n_ids`: how many ids the run created (default: all particles), `removed`: this
        rank's share of the ids removed so far (a checkpoint's; see Census), and
        `removals_done`: how many `remove` regions were applied already;
        `trigger_done`: whether the scene's `[trigger]` was applied already. Collective."""
        self.scene = scene
        self.slabs = slabs
        self.dim = dim = scene.dim
        self.kernels = kernels_for(dim)
        self.soil = soil_from_scene(scene)
        self.h = scene.h
        self.stepping = time_stepping(scene)
        self.t = t
        self.step = step
        self.first_step = step

        fresh = particles is None
        data = initial_particles(scene, slabs.reducer, slabs.slab) if fresh else particles
        recycle = scene.pressure.recycle if scene.pressure.scheme == "projection" else 0
        width = data["recycle_x"].shape[-1] if "recycle_x" in data else 0
        if width != recycle:  # a checkpoint's basis of another size: the guess starts anew
            data = {k: v for k, v in data.items() if not k.startswith("recycle_")}
        n_local = len(data["key"])
        self.n_global = int(slabs.reducer.sum(np.array([n_local], np.int64))[0])
        # ids run 0..n_ids-1; each is owned once or removed once (checked at snapshots)
        self.census = Census(slabs.comm, self.n_global if n_ids is None else n_ids, removed)
        self.n_ids = self.census.n_ids
        self.removals = sorted(scene.remove, key=lambda r: r.at)
        self.removals_done = removals_done
        # the recycled guess's basis (psph/solver/recycling.py): projection runs only
        self.recycle = recycle
        # rows for the owned particles and a quarter more for halo and wall ghosts; the
        # store grows by half when a step needs more (`ParticleStore.ensure`)
        self.store = ParticleStore(n_local + n_local // 4 + 256, dim, self.recycle)
        self.store.load(data)
        if fresh:
            self.store.u[:] = 0.0
            slabs.settle(self.store)  # seeded in 1D slabs; boxes along two axes take them

        lo, hi = scene.domain.min, scene.domain.max
        walls = plane_walls(scene.boundaries, lo, hi)
        self.wall_axis, self.wall_pos = walls.axis, walls.pos
        self.wall_sign, self.wall_fixed = walls.sign, walls.fixed
        # ghost velocities as on a free-slip wall, for the stretching rates (interactions.py);
        # without a fixed wall they are the velocities themselves
        nw = len(walls.sides)  # boundary particles: sort keys above every ghost's (corners
        # in 3D; the 2D keys as they were)
        stride = 1 + nw + nw * nw + (nw ** 3 if dim == 3 else 0)
        self.wall_particles = BoundaryParticles(scene, float(self.n_ids) * stride) \
            if has_boundary_particles(scene) else None
        self.halo = halo_width(scene)
        self._v_slip = np.zeros((0, dim)) if self.wall_fixed.any() or self.wall_particles else None
        self.ghost_src = np.zeros(0, np.int64)
        self.ghost_sign = np.ones(0)  # +1, or -1 for the ghosts of a drained wall
        # the initial lattice's extent, also on a restart (x - u of a checkpoint is not
        # its bits): from this slab's share of it
        self.drainage = Drainage(scene, walls.sides, lambda: extent(
            data["x"] if fresh else seed(scene, *slabs.slab, reducer=slabs.reducer)[0],
            slabs.reducer))
        self.pressure_solve = PressureSolve(self)
        self.solve = self.pressure_solve.stats

        margin = 2.0 * self.h
        self.box = np.array([c - margin for c in lo] + [c + margin for c in hi])
        self.cell_size = 2.0 * self.h
        self.softening = nonlocal_softening(scene, self.cell_size, self.wall_axis,
                                            self.wall_pos)  # None: local softening
        self.origin = np.array(lo, float) - 4.0 * self.cell_size
        span = np.array(hi, float) - np.array(lo, float)
        self.cell_max = (np.ceil(span / self.cell_size) + 8).astype(np.int64)
        # the grid of side 2h: the pair sweep's in 2D, the other cell-list kernels' in both
        self.cells = CellGrid(self.origin, self.cell_size, self.cell_max, self.store.cap)
        self._cell_arrays()
        # the pair sweep's grid: cells of side h in 3D (`neighbours.pair_cell_span`), a grid
        # of its own beside the one of side 2h, which the other cell-list kernels keep
        # and which is binned only for them; in 2D the sweep takes the grid of side 2h
        cells_per_2h = pair_cell_span(dim)
        self.pair_grid = None
        if cells_per_2h > 1:
            self.pair_grid = CellGrid(self.origin, self.cell_size / cells_per_2h,
                                      self.cell_max * cells_per_2h, self.store.cap)
        self.x_sorted = np.zeros((self.store.cap, dim))
        self.owned_before = np.zeros(self.store.cap + 1, np.int64)  # `count_owned`
        lay = self.layout = sum_layout(dim)
        # the Darcy sums (Q .. SUM_APSI) and the stress divergence, scaled by the lattice
        # moment after the sweep (`Stages._interactions`)
        self.darcy_columns = slice(lay.Q, lay.SUM_APSI + 1)
        self.dvdt_columns = slice(lay.DVDT, lay.DVDT + dim)
        # the pair sums of owned rows (halo and ghost rows get none): sized by `_neighbours`
        self.sums = np.zeros((0, lay.NSUMS))
        self.astress = np.zeros((1, 3 if dim == 2 else 6))
        self.w_dx = w_cubic(scene.particles.dx, self.h) if dim == 2 else \
            w_cubic_dim(scene.particles.dx, self.h, dim)
        # F~ of Eq. (23)
        self.lattice_norm = 1.0 / lattice_moment(scene.particles.dx, self.h, dim)
        self.scratch_moments = np.zeros((0, self.kernels.moment_columns))  # Shepard step
        self.scratch_trace = np.zeros(0)  # tr(sigma') before the stress filter
        self.scratch_shift = np.zeros((0, 5))  # grad C, the shift and 1/2 of `_shift`
        self.load_value = np.zeros(max(len(scene.loads), 1))

        g = scene.gravity
        self.body = tuple(float(c) for c in g)  # (b0, b1[, b2])
        self.b2 = self.body[2] if dim == 3 else 0.0
        self.body_force = np.array(self.body)  # for the ghosts' wall-normal stress (ghosts.py)
        self.head_b = self.soil.rho_l * np.array(self.body) if scene.pressure.scheme != "none" \
            else np.zeros(dim)
        # several materials: a row per material, indexed by the particle's
        # `material`; damping and the viscosity's sound speed from the stiffest one
        self.mat = material_table(scene)
        # the [trigger]: no softening before it, the reduced strength after it
        self.trigger_done = trigger_done
        self._mat_after_trigger = None
        if scene.trigger is not None:
            before, after = material_tables_of_trigger(scene, self.mat)
            self.mat = after if trigger_done else before
            self._mat_after_trigger = after
        self.stiff = stiffest(scene)
        self.damping = self.stiff.damping_coefficient(scene.stabilisation.damping, self.h)
        self.coupled = scene.pressure.scheme != "none"
        # weight of p in the pair stress of Eq. (26): 1 "pair", 0.5 "closure", 0 the others
        self.p_weight = {"pair": 1.0, "closure": 0.5}.get(scene.pressure.momentum, 0.0) \
            if self.coupled else 1.0
        self.av_sound_speed = (fastest_undrained(scene)
                               if self.coupled and scene.stabilisation.av_sound_speed
                               == "undrained" else self.stiff.sound_speed)
        self.plastic = any(m.model == "drucker_prager" for m in scene.material_list)
        self.dp = plasticity_parameters(scene)
        self.acc_term = self.coupled and scene.pressure.acceleration_term
        self.symplectic = scene.time.integrator == "symplectic"
        # free-surface pressure condition: 0 none, 1 ponding p <= 0, 2 drained p = 0
        self.ponding = {False: 0, True: 1, "drained": 2}[scene.pressure.ponding]
        # pairs of the last sweep, reused by the symplectic velocity sweep
        # (and by the mass-balance residual of the explicit and TPI pressure)
        self.shifting = scene.stabilisation.shifting
        self.record_pairs = self.symplectic or self.coupled or self.shifting > 0.0
        # row indices of this rank's store; sized by the first sweep that records them
        # (`Stages._interactions`: the step's pairs and an eighth more)
        self.pairs = np.zeros((0, 2), np.int32)
        self.pair_g = np.zeros((0, dim))
        self.n_pairs = 0
        self.dt, self.scheme = self.stepping.at(0.0)
        self.bad_particle = -1
        self.failure = None
        self.equilibrium = {}  # what `equilibrate` did
        # the grid of side 2h: the sweep's in 2D; in 3D only for the kernels that take it
        # (Shepard, the boundary particles, the non-local strain); unbinned, its arrays
        # are None, so that a kernel given them fails at once instead of finding nothing
        self.needs_cells = (self.pair_grid is None or self.softening is not None
                            or self.wall_particles is not None or self.shepard_filters)
        if not self.needs_cells:
            self.cells = None
            self._cell_arrays()
        self.passes = 0  # passes through the pipeline (a derived refresh follows its writers')
        self.stages = self._assemble()

    def _cell_arrays(self) -> None:
        """The grid of side 2h's arrays as the kernels take them (None where it is not
        binned); again after each binning, which may grow them."""
        g = self.cells
        self.cell_of, self.cell_start, self.order, self.ncell, self.grid_lo = (
            (g.cell_of, g.cell_start, g.order, g.ncell, g.lo) if g is not None
            else (None,) * 5)

    @property
    def shepard_filters(self) -> bool:
        """Whether the Shepard step runs: every `shepard_every` steps, on the pressure of a
        coupled scene or, if asked, on the stress (a dry scene has no pressure to
        filter)."""
        stab = self.scene.stabilisation
        return stab.shepard_every > 0 and (self.coupled or stab.shepard_stress)

    # ------------------------------------------------------------------ pipeline

    def _assemble(self) -> list[Stage]:
        """Only the stages the scene needs, in order, with the search and refreshes their
        declarations call for (`pipeline.assemble`)."""
        return assemble(self._physics_stages(), self._search_stages(), self._refresh_fields)

    def _search_stages(self) -> list[Stage]:
        """Halo, wall ghosts, boundary particles and cell lists of the current positions."""
        stages = []
        k = self.scene.decomposition.rebalance_every
        if self.slabs.size > 1 and k > 0:
            stages.append(Stage(f"rebalance[every {k}]", self._rebalance, every=k))
        if self.slabs.size > 1:
            stages.append(Stage("exchange", self._exchange))
        else:
            stages.append(Stage("reset_halo", self._reset_halo))
        if len(self.wall_axis):
            stages.append(Stage("ghosts", self._ghosts))
        if self.wall_particles:
            stages.append(Stage("boundary_rows", self._boundary_rows))
        stages.append(Stage("neighbours", self._neighbours))
        if self.wall_particles:
            stages.append(Stage("boundary_state", self._boundary_state))
        return stages

    def _physics_stages(self) -> list[Stage]:
        """The physics of a step, each stage with the fields it reads on neighbours and
        writes on owned rows."""
        every_field = frozenset(NEIGHBOUR_FIELDS)
        stages = []
        if self.coupled and self.drainage.has_planes:
            # exact sums over owned rows: the same before or after the exchange
            stages.append(Stage("drained_planes", self._drained_planes))
        stab = self.scene.stabilisation
        m = stab.shepard_every
        if self.shepard_filters:
            names, reads, writes = [], {"x", "vol"}, set()
            if self.coupled:
                names.append("shepard")
                reads |= {"p"}
                writes |= {"p", "p_prev"}
                if stab.pressure_filter_porosity:
                    writes |= {"poro", "vol", "rho", "perm"}
            if stab.shepard_stress:
                shepard = "stress" if self.coupled else "shepard_stress"
                names.append(shepard if stab.stress_filter == "shepard" else "mls_stress")
                reads |= {"stress"}
                writes |= {"stress"}
                if self.coupled and stab.stress_filter_porosity:
                    writes |= {"poro", "vol", "rho", "perm"}
            stages.append(Stage(f"{'+'.join(names)}[every {m}]", self._shepard, every=m,
                                reads=frozenset(reads), writes=frozenset(writes),
                                neighbours=True))
        name = "interactions[momentum" + (",pressure" if self.coupled else "") + \
            (",acceleration_term" if self.acc_term else "") + "]"
        stages.append(Stage(name, self._interactions, reads=every_field, neighbours=True))
        v_read = frozenset({"x", "v", "poro", "vol"})
        if self.symplectic:
            stages.append(Stage("kick", self._kick, writes=frozenset({"v", "acc"})))
            stages.append(Stage("velocity_sweep", self._velocity_sweep, reads=v_read,
                                neighbours=True))
        if self.stepping.scheme_main == SCHEME_PROJECTION:
            projecting = lambda: self.scheme == SCHEME_PROJECTION  # noqa: E731
            stages.append(Stage("pressure_solve[pcg,jacobi]+correction", self._project,
                                reads=frozenset({"x", "p", "poro", "vol", "rho", "perm"}),
                                writes=frozenset({"v", "p", "p_prev", "acc"}),
                                neighbours=True, when=projecting))
            stages.append(Stage("velocity_sweep[corrected]", self._velocity_sweep,
                                reads=v_read, neighbours=True, when=projecting))
        pname = {SCHEME_NONE: "dry", SCHEME_EXPLICIT: "explicit", SCHEME_TPI: "tpi",
                 SCHEME_PROJECTION: "projection"}[self.stepping.scheme_main]
        if self.stepping.scheme_main == SCHEME_TPI and self.stepping.explicit_until > 0:
            pname = "explicit->tpi"
        model = ",drucker_prager" if self.plastic else ",elastic"
        if self.softening:  # x as at the neighbour search: before shifting moves it
            stages.append(Stage(self.softening.name(), lambda: self.softening.average(
                self.store, self.cell_of, self.cell_start, self.order, self.ncell),
                reads=frozenset({"x", "vol"}), neighbours=True))
        if self.shifting > 0.0:
            # before the update: the sweep's volumes, which the update changes on owned
            # rows only (halo copies keep them), so the sums stay partition-independent
            stages.append(Stage("shifting", self._shift, reads=frozenset({"x", "vol"}),
                                writes=frozenset({"x"}), neighbours=True))
        stages.append(Stage(f"update[{pname}{model}]", self._update, writes=every_field))
        return stages

    def state_bytes(self) -> int:
        """Bytes of the running state on this rank: the particle store's arrays and the
        simulation's own (scratch, cell lists, the pair grid's, pair lists, bookkeeping)."""
        grids = [vars(g).values() for g in (self.cells, self.pair_grid) if g is not None]
        arrays = {id(a): a for a in (*self.store.arrays.values(), *vars(self).values(),
                                     *(a for g in grids for a in g))
                  if isinstance(a, np.ndarray)}  # each once: the grids' are attributes too
        return int(sum(a.nbytes for a in arrays.values()))

    # ------------------------------------------------------------------ stepping

    def apply_removals(self) -> int:
        """Remove the particles inside every `remove` region whose time has come
        (collective: t is the same on every rank). Returns how many were removed."""
        removed = 0
        while (self.removals_done < len(self.removals)
               and self.t >= self.removals[self.removals_done].at * (1 - 1e-12)):
            rm = self.removals[self.removals_done]
            st = self.store
            n = st.n_owned
            x = st.x[:n]
            inside = removal_region(x, rm, self.scene.particles.dx, self.slabs.reducer)
            ids = st.key[:n][inside].astype(np.int64)
            keep = np.flatnonzero(~inside)
            for a in st.all_rows:
                a[:len(keep)] = a[keep]
            st.n_owned = len(keep)
            st.n_halo = st.n_ghost = 0
            removed += self.census.remove(ids)
            self.n_global = self.census.n_alive
            self.removals_done += 1
        return removed

    def apply_trigger(self) -> None:
        """The scene's `[trigger]` once its time has come (t is the same on every rank):
        the reduced strength and softening from now on; the plastic strain and work set to
        0 if asked, on every row (halo copies come with the next exchange)."""
        if self._mat_after_trigger is None or self.trigger_done \
                or self.t < self.scene.trigger.at * (1 - 1e-12):
            return
        self.mat = self._mat_after_trigger
        if self.scene.trigger.reset_plastic_strain:
            self.store.eps_p[:] = 0.0
            self.store.plastic_work[:] = 0.0
        self.trigger_done = True

    def _run_pipeline(self, stages: list[Stage], timed: bool = True) -> None:
        """One pass of `stages` at this step: each that is due runs (and is timed)."""
        self.passes += 1
        timer = time.perf_counter
        for stage in stages:
            if not stage.due(self.step, self.passes):
                continue
            t0 = timer()
            stage.run()
            stage.last_pass = self.passes
            if timed:
                stage.seconds += timer() - t0
                stage.calls += 1

    def advance_one(self) -> None:
        """One step of the pipeline: removals due, dt and scheme at t, the stages."""
        if self.removals_done < len(self.removals):
            self.apply_removals()
        if not self.trigger_done:
            self.apply_trigger()
        self.dt, self.scheme = self.stepping.at(self.t)
        self._run_pipeline(self.stages)
        self.t += self.dt
        self.step += 1

    def equilibrate(self) -> dict:
        """Gravity loading before t = 0 (collective; Section 4.5: "followed by
        gravitational loading to obtain the initial in-situ stress conditions").

        The K0 state of `initial.k0` is in equilibrium only under level ground: under a
        slope face or at the free end of a block it unloads at t = 0, and a nearly
        undrained soil answers that unloading with suction. For
        `initial.equilibrate` seconds the step pipeline runs with the pore pressure held
        at its hydrostatic value (drained, the steady state of the water table), no
        removals, no Shepard or rebalancing, and the global damping of Eq. (43)-(44) at
        eta_d = `initial.equilibrate_damping`; the clock stays at 0. Then velocities and
        displacements are zeroed, so the run starts at rest from the relaxed stress.
        Returns what it did, for summary.json."""
        ini = self.scene.initial
        if ini.equilibrate <= 0.0 or self.step > 0:
            return {}
        steps = int(math.ceil(ini.equilibrate / self.stepping.dt_main))
        dt_scheme = (self.dt, self.scheme)
        damping = self.damping
        self.dt, self.scheme = self.stepping.dt_main, SCHEME_NONE
        self.damping = self.stiff.damping_coefficient(ini.equilibrate_damping, self.h)
        stages = [s for s in self.stages if s.every == 1]
        wall0 = time.perf_counter()
        for _ in range(steps):
            self._run_pipeline(stages, timed=False)
        self.dt, self.scheme = dt_scheme
        self.damping = damping
        self.check_failure()
        st = self.store
        n = st.n_owned
        speed = float(np.sqrt((st.v[:n] ** 2).sum(axis=1)).max()) if n else 0.0
        speed = self.slabs.allreduce_max(speed)
        st.v[:n] = 0.0
        st.u[:n] = 0.0
        st.acc[:n] = 0.0
        self.equilibrium = {"seconds_simulated": steps * self.dt, "steps": steps,
                "eta_d": ini.equilibrate_damping, "max_speed_at_end_m_s": speed,
                "wall_s": time.perf_counter() - wall0}
        return self.equilibrium

    def check_failure(self) -> None:
        """Collective: all ranks raise NumericalError if any rank saw a non-finite value."""
        if self.slabs.any(self.failure is not None):
            self.raise_failure()

    def raise_failure(self) -> None:
        """Collective, once some rank has failed: every rank raises the same error, naming
        the earliest failure (lowest step, then rank)."""
        info = self.slabs.comm.allgather(self.failure)
        f = min((i for i in info if i is not None), key=lambda i: (i[0], i[3]))
        raise NumericalError(f"step {f[0]}, t = {f[1]:.6g} s, particle id {f[2]} "
                             f"(rank {f[3]}): field {f[4]}")

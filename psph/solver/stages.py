"""The work of each stage of a step (`Simulation` declares them and
`psph/solver/pipeline.py` assembles them): the search (exchange, ghosts, boundary rows,
neighbours), the refresh of fields written since, and the physics (drained planes, the
Shepard filter, the pair sweep, the symplectic kick, the velocity sweep, the projection,
shifting and the update). Each works on the simulation's particle store and scratch
arrays."""

import numpy as np

from psph.kernels.artificial_stress import artificial_stress
from psph.kernels.bundles import (
    CellList,
    Cells,
    PairFields,
    PairParams,
    PairRecord,
    PorosityFields,
    StepParams,
    SurfaceLoads,
    UpdateFields,
    fields_of,
)
from psph.kernels.ghosts import make_ghosts, wall_contact
from psph.kernels.interactions import symmetric_gradient_sums
from psph.kernels.neighbours import count_owned, gather_sorted
from psph.kernels.shifting import (
    FREE_TRACE,
    SHIFT_CAP,
    SURFACE_TRACE,
    SURFACE_TRACE_3D,
    shift_particles,
    shift_particles_3d,
)
from psph.kernels.update import (
    SCHEME_PROJECTION,
    SCHEME_TPI,
    pore_pressure_force,
    porosity_follows_pressure_filter,
    porosity_follows_stress_filter,
)
from psph.physics.loads import load_values
from psph.state.particles import ParticleStore


class Stages:
    """The stage methods of `Simulation` (its state is set up by `Simulation.__init__`)."""

    def _reset_halo(self) -> None:
        self.store.n_halo = self.store.n_ghost = 0

    def _rebalance(self) -> None:
        self.slabs.rebalance(self.store, self.halo,
                             self.scene.decomposition.imbalance_threshold)

    def _exchange(self) -> None:
        self.slabs.exchange(self.store, self.halo)

    @property
    def v_slip(self) -> np.ndarray:
        """Velocities with wall ghosts mirrored as on a free-slip wall (every row)."""
        if self._v_slip is None:
            return self.store.v
        if self._v_slip.shape[0] < self.store.cap:
            self._v_slip = np.zeros((self.store.cap, self.dim))
        return self._v_slip

    def _ghosts(self) -> None:
        from psph.kernels.bundles import GhostSources, WallFields, Walls

        st = self.store
        while True:
            if self.ghost_src.shape[0] < st.cap:
                self.ghost_src = np.zeros(st.cap, np.int64)
                self.ghost_sign = np.ones(st.cap)
            walls = Walls(self.wall_axis, self.wall_pos, self.wall_sign, self.wall_fixed,
                          self.drainage.update_walls(self.t))
            ng = make_ghosts(st.n_real, st.cap, 2.0 * self.h, float(self.n_ids), walls,
                             fields_of(WallFields, st.arrays, v_slip=self.v_slip),
                             self.head_b, self.body_force,
                             GhostSources(self.ghost_src, self.ghost_sign))
            if ng >= 0:
                st.n_ghost = ng
                return
            st.ensure(st.cap + st.cap // 2)

    def _boundary_rows(self) -> None:
        """Rows of the boundary particles near this slab, after the ghosts."""
        self.wall_particles.select(self.slabs.region)
        while not self.wall_particles.append(self.store):
            if len(self.wall_axis):  # the store grew: ghosts again (v_slip was reset)
                self._ghosts()

    def _boundary_state(self) -> None:
        self.wall_particles.state(self.store, self.v_slip, self.head_b, self.body_force,
                                  self.cell_of, self.cell_start, self.order, self.ncell)

    def _refresh_fields(self, fields: tuple[str, ...]) -> None:
        """The owners' current `fields` into the halo, then the wall ghosts and boundary
        particles again from the real rows (the same neighbours: nothing has moved)."""
        st = self.store
        self.slabs.refresh_halo(*(st.arrays[f] for f in fields))
        self._refresh_walls()

    def _refresh_walls(self) -> None:
        """Wall ghosts and boundary particles again from the current real rows."""
        n_ghost = self.store.n_ghost  # the wall ghosts' count is unchanged
        if len(self.wall_axis):
            self._ghosts()
        if self.wall_particles:
            self.store.n_ghost = n_ghost
            self._boundary_state()

    def _neighbours(self) -> None:
        st = self.store
        n = st.n_total
        if self.sums.shape[0] < st.n_owned:  # every kernel writes and reads owned rows only
            self.sums = np.zeros((st.n_owned + st.n_owned // 8 + 64, self.layout.NSUMS))
        if self.pair_grid is not None:
            self.pair_grid.bin(st.x, st.key, n)
        if not self.needs_cells:
            return
        self.cells.bin(st.x, st.key, n)
        self._cell_arrays()

    def _drained_planes(self) -> None:
        """The free drained sides' planes at this step (collective)."""
        self.drainage.update_planes(self.t, self.store, self.slabs)

    def _shepard(self) -> None:
        """Eq. (46) on owned particles: the pressure in a coupled scene, the stress if
        `shepard_stress` (the pipeline then refreshes the copies of what it wrote)."""
        st = self.store
        if self.scratch_moments.shape[0] < st.cap:
            self.scratch_moments = np.zeros((st.cap, self.kernels.moment_columns))
            self.scratch_trace = np.zeros(st.cap)
        mom = self.scratch_moments
        cells = CellList(self.cell_of, self.cell_start, self.order, self.ncell)
        stab = self.scene.stabilisation
        s = self.soil
        if self.coupled and stab.pressure_filter_porosity:
            p_before = self.scratch_trace[:st.n_owned]
            p_before[:] = st.p[:st.n_owned]
        if self.coupled:
            self.kernels.shepard_pressure(st.n_total, st.n_owned, st.x, st.p, st.p_prev,
                                          st.vol, st.drained_from,
                                          self.drainage.layer_clock(self.t), cells, self.h,
                                          mom)
        if self.coupled and stab.pressure_filter_porosity:
            porosity_follows_pressure_filter(
                st.n_owned, p_before, st.p, fields_of(PorosityFields, st.arrays), s.rho_l,
                self.mat, st.material, s.K_l)
        if stab.shepard_stress:
            stress_filter = self.kernels.mls_stress if stab.stress_filter == "mls" \
                else self.kernels.shepard_stress
            # a dry scene's porosity does not follow its strain (Eq. 24 is not solved)
            follow = self.coupled and stab.stress_filter_porosity
            if follow:
                trace = self.scratch_trace[:st.n_owned]
                np.sum(st.stress[:st.n_owned, :3], axis=1, out=trace)
            stress_filter(st.n_total, st.n_owned, st.x, st.stress, st.vol, cells, self.h, mom)
            if follow:
                porosity_follows_stress_filter(
                    st.n_owned, trace, st.stress, fields_of(PorosityFields, st.arrays),
                    s.rho_l, self.mat, st.material)

    def _interactions(self) -> None:
        st = self.store
        rl = self.soil.rho_l
        alpha = self.scene.pressure.alpha if self.scheme == SCHEME_TPI else 0.0
        sb = self.scene.stabilisation
        as_n = 0.0
        if sb.artificial_stress > 0.0:
            if self.astress.shape[0] < st.cap:
                self.astress = np.zeros((st.cap, self.astress.shape[1]))
            artificial_stress(st.n_total, st.stress, sb.artificial_stress, self.astress)
            as_n = sb.artificial_stress_n
        fields = fields_of(PairFields, st.arrays, v_slip=self.v_slip, astress=self.astress)
        grid = self.pair_grid
        cell_start, order, ncell = ((self.cell_start, self.order, self.ncell) if grid is None
                                    else (grid.cell_start, grid.order, grid.ncell))
        n_slots = int(cell_start[int(np.prod(ncell))])
        if self.x_sorted.shape[0] < n_slots:
            self.x_sorted = np.zeros((st.cap, self.dim))
        gather_sorted(st.x, order, n_slots, self.x_sorted)
        if self.owned_before.shape[0] < n_slots + 1:
            self.owned_before = np.zeros(st.cap + 1, np.int64)
        count_owned(order, n_slots, st.n_owned, self.owned_before)
        cells = Cells(cell_start, order, ncell, self.x_sorted, self.owned_before)
        par = PairParams(self.h, alpha, sb.av_alpha, sb.av_beta, self.av_sound_speed,
                         rl * self.body[0], rl * self.body[1], self.coupled, self.acc_term,
                         as_n, self.w_dx, self.p_weight, self.record_pairs,
                         rl * self.b2).typed()
        while True:
            n = self.kernels.pair_sums(st.n_total, st.n_owned, st.n_real, fields, cells, par,
                                       self.sums, PairRecord(self.pairs, self.pair_g))
            if n >= 0:
                self.n_pairs = n
                if self.coupled and self.drainage.has_planes:
                    self.kernels.image_sums(st.n_owned, n, self.pairs, fields,
                                            self.drainage.planes, par, self.sums)
                if self.coupled:
                    self.sums[:st.n_owned, self.darcy_columns] *= self.lattice_norm
                # the stress divergence of Eq. (26) has the same lattice moment: a
                # uniform stress under a surface load balanced m0 q, not q
                self.sums[:st.n_owned, self.dvdt_columns] *= self.lattice_norm
                if self.p_weight < 1.0:
                    pore_pressure_force(st.n_owned, self.sums, st.rho,
                                        self.scene.pressure.momentum == "gradient",
                                        self.lattice_norm, 1.0 - self.p_weight)
                return
            grow = -n + (-n) // 8 + 1024  # this step's pairs and an eighth more
            self.pairs = np.zeros((grow, 2), np.int32)
            self.pair_g = np.zeros((grow, self.dim))

    def _kick(self) -> None:
        """Symplectic step: v^(n+1) from the accelerations of step n (Eq. 45)."""
        st = self.store
        load_values(self.scene.loads, self.t, self.load_value)
        self.kernels.kick(st.n_owned, self.sums, fields_of(UpdateFields, st.arrays),
                          SurfaceLoads(st.load_index, st.traction, self.load_value),
                          self.body[0], self.body[1], self.damping, self.dt, self.b2)

    def _velocity_sweep(self) -> None:
        """The velocity sums again from the current v over the pairs of this step's sweep:
        after the kick, the rates of Eq. (11), (24), (25) take v^(n+1) (the staggered
        order of Eq. 27); after the projection, the corrected velocity."""
        st = self.store
        self.kernels.velocity_gradient_sums(st.n_owned, st.n_real, self.n_pairs, self.pairs,
                                            self.pair_g, st.v, self.v_slip, st.poro, st.vol,
                                            self.coupled, self.sums)

    def _update(self) -> None:
        st = self.store
        s = self.soil
        load_values(self.scene.loads, self.t, self.load_value)
        par = StepParams(self.dt, self.drainage.layer_clock(self.t), s.K_l, s.gamma_l, s.rho_l,
                         self.body[0], self.body[1], self.damping, self.scheme,
                         self.scene.pressure.beta, self.acc_term,
                         self.scene.stabilisation.corrected_strain_rate, self.plastic,
                         self.ponding, self.symplectic, self.b2).typed()
        bad = self.kernels.advance(st.n_owned, self.sums, fields_of(UpdateFields, st.arrays),
                      SurfaceLoads(st.load_index, st.traction, self.load_value), self.mat,
                      self.softening.eps_hat if self.softening else st.eps_p, self.box, par)
        if bad >= 0 and self.failure is None:  # named before any wall moves it back
            what = _bad_field(st, bad)
            self.failure = (self.step, self.t, int(st.key[bad]), self.slabs.rank, what)
        if self.scheme == SCHEME_PROJECTION and not self.symplectic:
            st.acc[:st.n_owned] += self.pressure_solve.correction_acceleration()
        if len(self.wall_axis):
            wall_contact(st.n_owned, st.x, st.v, st.u, self.wall_axis, self.wall_pos,
                         self.wall_sign)
        if self.wall_particles:
            self.wall_particles.contact(st, self.origin, self.cell_size, self.grid_lo,
                                        self.ncell, self.cell_start, self.order, self.dt)

    def _shift(self) -> None:
        """Particle shifting (`stabilisation.shifting`, psph/kernels/shifting.py) over the
        pairs and volumes of this step's sweep; the update that follows moves x by dt v
        and puts back a particle found beyond a wall."""
        st = self.store
        d = self.dim
        if self.scratch_shift.shape[0] < st.cap:
            self.scratch_shift = np.zeros((st.cap, 2 * d + 1))
            self.scratch_shift[:, 2 * d] = 0.5  # grad C_i = sum_j V_j (1/2 + 1/2) grad_i W_ij
        half = self.scratch_shift[:, 2 * d]
        grad_c = self.scratch_shift[:, 0:d]
        symmetric_gradient_sums(st.n_owned, self.n_pairs, self.pairs, self.pair_g, st.vol,
                                half, grad_c)
        cap = SHIFT_CAP * self.scene.particles.dx
        if d == 2:
            shift_particles(st.n_owned, grad_c, self.sums, self.shifting, self.h, self.dt, cap,
                            SURFACE_TRACE, FREE_TRACE, st.x, self.scratch_shift[:, d:2 * d])
        else:
            shift_particles_3d(st.n_owned, grad_c, self.sums, self.shifting, self.h, self.dt,
                               cap, SURFACE_TRACE_3D, st.x, self.scratch_shift[:, d:2 * d])

    def mass_balance_residual(self) -> float:
        """`PressureSolve.residual` of this step (collective)."""
        return self.pressure_solve.residual()

    def _project(self) -> None:
        """The pressure increment of the step from one solve of Eq. (29) with its velocity
        correction (`PressureSolve.project`). After the kick (symplectic step) or, in the
        one-sweep step, of v^n from the step's sweep; the update then kicks with a^n.
        Collective. Declared only while the projection is in force (the gravity loading of
        `equilibrate` holds p hydrostatic)."""
        self.pressure_solve.project()


def _bad_field(st: ParticleStore, i: int) -> str:
    """Name and value of the first non-finite (or beyond 1e300) field of particle row i,
    else a porosity outside (0, 1), else the position of a particle that left the domain."""
    for name in ("p", "v", "stress", "x"):
        value = np.asarray(st.arrays[name][i])
        if not np.all(np.isfinite(value)):
            return f"{name} = {value.tolist()} (not finite)"
        if not np.all(np.abs(value) < 1e300):
            return f"{name} = {value.tolist()} (diverged)"
    if not 0.0 < st.poro[i] < 1.0:
        return f"n = {st.poro[i]} (porosity outside (0, 1), Eq. 24)"
    return f"x = {st.x[i].tolist()} (left the domain)"

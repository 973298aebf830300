"""Permeability from the void ratio, Eq. (4), and the ponding condition p <= 0 (or the
drained p = 0) on the free surface (Section 4.4), through one or a few coupled steps."""

import numpy as np

from psph.app.run import make_slabs
from psph.config.load import load_scene
from psph.solver.simulation import Simulation


def _sim(overrides):
    from mpi4py import MPI

    scene = load_scene("geostatic_column", overrides)
    return Simulation(scene, make_slabs(scene, MPI.COMM_SELF))


def test_permeability_follows_the_void_ratio_eq4():
    sim = _sim(["material.C_k=2.0", "initial.k0=0.3"])  # off-equilibrium: porosity moves
    for _ in range(200):
        sim.advance_one()
    st = sim.store
    n, n0 = st.poro[:st.n_owned], st.poro0[:st.n_owned]
    e, e0 = n / (1 - n), n0 / (1 - n0)
    assert np.max(np.abs(n - n0)) > 1e-7  # the test would be empty otherwise
    expected = 2.0e-4 * np.exp((e - e0) / 2.0)
    assert np.allclose(st.perm[:st.n_owned], expected, rtol=1e-12, atol=0)


def test_constant_permeability_without_c_k():
    sim = _sim(["initial.k0=0.3"])
    for _ in range(50):
        sim.advance_one()
    assert np.all(sim.store.perm[:sim.store.n_owned] == 2.0e-4)


def test_ponding_keeps_free_surface_pressure_non_positive():
    # water table above the surface and an impermeable top: only ponding removes p > 0
    over = ["initial.water_table=2.5", "boundaries.top.flow='impermeable'"]
    plain = _sim(over)
    pond = _sim(over + ["pressure.ponding=true"])
    for sim in (plain, pond):
        sim.advance_one()
    top = lambda s: s.store.x[:s.store.n_owned, 1] > 1.95  # noqa: E731
    assert np.all(plain.store.p[:plain.store.n_owned][top(plain)] > 4000.0)
    assert np.all(pond.store.p[:pond.store.n_owned][top(pond)] <= 0.0)
    below = pond.store.x[:pond.store.n_owned, 1] < 1.8
    assert np.all(pond.store.p[:pond.store.n_owned][below] > 4000.0)  # interior untouched


def test_drained_free_surface_holds_no_suction_either():
    over = ["boundaries.top.flow='impermeable'"]
    pond = _sim(over + ["pressure.ponding=true"])
    drained = _sim(over + ['pressure.ponding="drained"'])
    top = lambda s: s.store.x[:s.store.n_owned, 1] > 1.95  # noqa: E731
    for sim in (pond, drained):
        sim.store.p[:sim.store.n_owned][top(sim)] = -5000.0  # the top layer in suction
        sim.store.p_prev[:sim.store.n_owned][top(sim)] = -5000.0
        sim.advance_one()
    assert np.all(pond.store.p[:pond.store.n_owned][top(pond)] < -3000.0)  # kept by ponding
    assert np.all(drained.store.p[:drained.store.n_owned][top(drained)] == 0.0)
    below = drained.store.x[:drained.store.n_owned, 1] < 1.8
    assert np.all(drained.store.p[:drained.store.n_owned][below] > 1000.0)  # interior untouched


def test_porosity_floor_holds():
    floor = 0.35 - 1e-9  # the column's n0 is 0.35: any compaction reaches the floor
    free, floored = _sim(["initial.k0=0.3"]), _sim(["initial.k0=0.3",
                                                    f"material.porosity_min={floor}"])
    for _ in range(200):
        free.advance_one()
        floored.advance_one()
    n_free = free.store.poro[:free.store.n_owned]
    n_floor = floored.store.poro[:floored.store.n_owned]
    assert n_free.min() < floor  # without the floor the column compacts below it
    assert n_floor.min() == floor and np.sum(n_floor == floor) > 0


def test_porosity_leaving_0_1_is_a_named_numerical_failure():
    sim = _sim([])
    sim.store.poro[7] = 1.2  # e.g. a particle torn apart: its volume would change sign
    sim.advance_one()
    step, t, pid, rank, what = sim.failure
    assert step == 0 and pid == int(sim.store.key[7]) and what.startswith("n = 1.2")

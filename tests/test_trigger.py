"""The [trigger] of a scene: the gravity loading at peak strength without softening, then
the strength divided by a factor and softening from the trigger's time on (del Castillo,
Borja and Fávero Neto 2026, doi:10.1002/nag.70322), once, also across a restart."""

import math

import numpy as np
import pytest

from psph.config.load import load_scene
from psph.errors import SceneError
from psph.kernels.update import MAT_DP
from psph.physics.material import material_table, material_tables_of_trigger

SMALL = ["particles.dx=4.0", "initial.equilibrate=0.0", "time.end=0.01"]
TRIGGER = ["trigger.at=0.0", "trigger.strength_factor=1.65"]


def _scene(extra):
    return load_scene("retrogressive_k0_0.5", SMALL + extra)


def test_tables_before_and_after():
    scene = _scene(TRIGGER)
    table = material_table(scene)
    before, after = material_tables_of_trigger(scene, table)
    phi_p, phi_r, c_p, c_r, _, eta, _ = table[0, MAT_DP:MAT_DP + 7]
    assert before[0, MAT_DP + 5] == 0.0 and eta == 5.0
    assert np.array_equal(np.delete(before, MAT_DP + 5, axis=1),
                          np.delete(table, MAT_DP + 5, axis=1))
    assert after[0, MAT_DP + 5] == eta
    assert after[0, MAT_DP + 2] == pytest.approx(c_p / 1.65)
    assert after[0, MAT_DP + 3] == pytest.approx(c_r / 1.65)
    assert math.tan(after[0, MAT_DP]) == pytest.approx(math.tan(phi_p) / 1.65)
    assert math.tan(after[0, MAT_DP + 1]) == pytest.approx(math.tan(phi_r) / 1.65)
    kept = _scene(TRIGGER + ["trigger.reduce_residual=false"])
    _, after_kept = material_tables_of_trigger(kept, material_table(kept))
    assert after_kept[0, MAT_DP + 3] == c_r and after_kept[0, MAT_DP + 1] == phi_r


def test_a_trigger_needs_a_softening_material():
    with pytest.raises(SceneError, match="trigger"):
        load_scene("terzaghi", ["trigger.at=0.0"])
    with pytest.raises(SceneError, match="strength_factor"):
        _scene(["trigger.strength_factor=0.5"])


def test_applied_once_and_not_again_after_a_restart():
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.solver.simulation import Simulation

    scene = _scene(TRIGGER)
    before, after = material_tables_of_trigger(scene, material_table(scene))
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
    assert np.array_equal(sim.mat, before) and not sim.trigger_done
    sim.store.eps_p[:] = 0.25  # as if the loading had yielded
    sim.advance_one()
    assert sim.trigger_done and np.array_equal(sim.mat, after)
    assert np.all(sim.store.eps_p[:sim.store.n_owned] < 0.25)
    sim.store.eps_p[:] = 0.5
    sim.apply_trigger()  # done: no second reset
    assert np.all(sim.store.eps_p == 0.5)
    restarted = Simulation(scene, make_slabs(scene, MPI.COMM_SELF), t=0.01, step=10,
                           trigger_done=True)
    assert np.array_equal(restarted.mat, after)
    restarted.store.eps_p[:] = 0.5
    restarted.advance_one()
    assert np.all(restarted.store.eps_p[:restarted.store.n_owned] >= 0.5)


def test_a_scene_without_a_trigger_keeps_its_table():
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.solver.simulation import Simulation

    scene = _scene([])
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
    assert np.array_equal(sim.mat, material_table(scene)) and not sim.trigger_done


def test_no_flow_is_k_zero_with_the_explicit_scheme(tmp_path):
    """k = 0: the pore water cannot move, p follows the volumetric strain (Eq. 25 without
    its Darcy term); Eq. (42) sets no limit; TPI, which has no storage, refuses it."""
    from mpi4py import MPI

    from psph.app.run import run
    from psph.solver.stepping import time_stepping

    with pytest.raises(SceneError, match="material.k"):
        load_scene("terzaghi_tpi", ["material.k=0.0"])
    scene = _scene(["material.k=0.0", "time.end=0.02"])
    st = time_stepping(scene)
    assert st.limits["dt_fluid_eq42"] is None and math.isfinite(st.dt_main)
    summary = run(scene, tmp_path, comm=MPI.COMM_SELF, quiet=True)
    assert summary["status"] == "finished" and summary["steps"] == 50

"""The symplectic step (`time.integrator = "symplectic"`): the velocity sweep over the
pairs recorded by `pair_sums` gives the same velocity sums, and the step runs the
Section 4.5 clay slope at the paper's dt = 4e-4 s (3x the undrained limit of Eq. 41),
where the one-sweep step diverges."""

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.errors import NumericalError
from psph.kernels.interactions import velocity_gradient_sums
from psph.kernels.sum_columns import GS, MOMENT
from psph.physics.limits import undrained_dt_limit
from tests.helpers import sums_for

VELOCITY_COLUMNS = [4, 5, 6, 7, 10, 11, 12, 13, 25, 26, 27, 28]


def _cloud(n_side=12, seed=3):
    rng = np.random.default_rng(seed)
    dx = 0.1
    g = (np.arange(n_side) + 0.5) * dx
    x = np.array(np.meshgrid(g, g)).reshape(2, -1).T + rng.uniform(-0.2, 0.2, (n_side**2, 2)) * dx
    return x, dx, rng


@pytest.mark.parametrize("n_ghost", [0, 30])
def test_velocity_sweep_over_recorded_pairs_equals_pair_sums(n_ghost):
    """With n_ghost > 0 the last rows stand for wall ghosts whose free-slip velocity
    (v_slip) differs from v, so the stretching correction Gs is exercised too."""
    x, dx, rng = _cloud()
    n = len(x)
    n_real = n - n_ghost
    vol = np.full(n, dx * dx)
    poro = rng.uniform(0.3, 0.5, n)
    v_old, v_new = rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
    slip_old, slip_new = v_old.copy(), v_new.copy()
    slip_old[n_real:, 0] *= -1.0
    slip_new[n_real:, 0] *= -1.0
    pairs = (np.zeros((40 * n, 2), np.int64), np.zeros((40 * n, 2)))
    sums, n_pairs = sums_for(x, 1.3 * dx, vol, v=v_old, poro=poro, pairs=pairs,
                             v_slip=slip_old, n_owned=n_real, n_real=n_real)
    assert n_pairs > 4 * n
    velocity_gradient_sums(n_real, n_real, n_pairs, pairs[0], pairs[1], v_new, slip_new,
                           poro, vol, True, sums)
    expected = sums_for(x, 1.3 * dx, vol, v=v_new, poro=poro, v_slip=slip_new,
                        n_owned=n_real, n_real=n_real)
    # same pairs, same order: the same floating-point sums
    assert np.array_equal(sums[:, VELOCITY_COLUMNS], expected[:, VELOCITY_COLUMNS])
    assert np.array_equal(sums[:, MOMENT], expected[:, MOMENT])  # the rest is left alone
    assert sums[:n_real, GS].any() == (n_ghost > 0)


def test_a_short_pair_list_is_reported_and_the_sums_stay_complete():
    from psph.kernels.bundles import PairFields, PairParams, PairRecord, sorted_cells
    from psph.kernels.interactions import pair_sums
    from psph.kernels.sum_columns import NSUMS
    from tests.helpers import cell_lists

    x, dx, rng = _cloud(6)
    n, h = len(x), 0.13
    z = np.zeros
    cell_start, order, ncell = cell_lists(x, h)
    out = []
    for cap in (3, 10 * n * 40):
        sums = z((n, NSUMS))
        fields = PairFields(x, z((n, 2)), z((n, 2)), z((n, 4)), z(n), z(n), np.full(n, 0.4),
                            np.full(n, dx * dx), np.ones(n), np.ones(n), z((n, 2)), z((n, 3)))
        got = pair_sums(n, n, n, fields, sorted_cells(cell_start, order, ncell, x),
                        PairParams(h, record=True).typed(), sums,
                        PairRecord(z((cap, 2), np.int64), z((cap, 2))))
        out.append((got, sums))
    assert out[1][0] > 3 and out[0][0] == -out[1][0]  # too short: minus the pairs' count
    assert np.array_equal(out[0][1], out[1][1])


@pytest.fixture(scope="module")
def clay_window(tmp_path_factory):
    """retrogressive_k0_0.5 to t = 0.3 s on one rank with each integrator, the viscosity at
    the skeleton's sound speed as when this was measured: with the scene's undrained one
    (issue 13, cause 10) the one-sweep step runs through 0.3 s too (`psph run
    retrogressive_k0_0.5 --set 'time.integrator="euler"' --set time.end=0.3`, 2026-11-29),
    the viscosity then damping the undrained mode that diverged. Without the particle
    shifting the scene took later (issue 13, cause 12), as measured. Without the scene's
    2 s of gravity loading (`initial.equilibrate`, 5,000 steps a run, nine tenths
    of this test's time): the step, not the initial state, is under test (measured
    2026-12-01: the one-sweep step stops at 0.115 s with the porosity of particle 1295
    at 0, the symplectic one finishes)."""
    from mpi4py import MPI

    results = {}
    for integrator in ("euler", "symplectic"):
        out = tmp_path_factory.mktemp(integrator)
        scene = load_scene("retrogressive_k0_0.5", [f'time.integrator="{integrator}"',
                                                    "time.end=0.3", "output.interval=0.1",
                                                    "output.times=[]",
                                                    'stabilisation.av_sound_speed="solid"',
                                                    "stabilisation.shifting=0.0",
                                                    "initial.equilibrate=0.0"])
        try:
            results[integrator] = run(scene, out, comm=MPI.COMM_SELF, quiet=True)
        except NumericalError as e:
            results[integrator] = e
    return scene, results


def test_clay_slope_at_the_papers_dt_needs_the_symplectic_step(clay_window):
    scene, results = clay_window
    assert scene.time.dt == 4e-4 and scene.time.dt > 3 * undrained_dt_limit(scene)
    assert isinstance(results["euler"], NumericalError)  # measured: stops at 0.115 s
    assert results["symplectic"]["status"] == "finished"
    assert results["symplectic"]["end_time_s"] == pytest.approx(0.3)

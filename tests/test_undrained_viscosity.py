"""The artificial viscosity's sound speed in an explicit coupled scene (issue 13, cause 10).

With explicit Eq. (25) the pore water adds K_l / n to the skeleton's stiffness: pressure
disturbances travel at c_sp of Eq. (28) (359 m/s for the Section 4.5 clay), five times the
skeleton's sqrt(E / rho_s) (69 m/s) with which the Monaghan term of Eq. (26) was scaled.
In `retrogressive_k0_0.5` that left single-particle pressure spikes in the liquefied base,
+200 kPa over their neighbours (519 kPa against 390 kPa of overburden at 12 s);
`stabilisation.av_sound_speed = "undrained"` damps them (max 365 kPa through 12 s).

Here: a saturated elastic block at rest (16 x 8 particles of that clay) whose particles
get a random velocity of 0.5 m/s rms (the approach of neighbours that made those spikes),
run for 100 steps at the slope's dt. The pressure noise that stirs up (p minus the same
block's p without the kick) is, measured: 60.3 kPa rms with the skeleton's sound speed,
24.1 kPa with the undrained one. With noise put into p itself instead (20 kPa rms), both
speeds leave about the same after 150 steps (3.6 against 3.0 kPa): the viscosity acts on
approaching particles, not on p.
"""

import numpy as np
import pytest

from bench.studies.sliding import block_scene

STEPS = 100


def _pressure_after_kick(sound: str, kick_rms: float) -> np.ndarray:
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.solver.simulation import Simulation

    scene = block_scene(['material.model="elastic"', 'boundaries.bottom.motion="slip"',
                         f'stabilisation.av_sound_speed="{sound}"'], nx=16, ny=8)
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
    st = sim.store
    n = st.n_owned
    rng = np.random.default_rng(7)
    order = np.argsort(st.key[:n])
    kick = np.empty((n, 2))
    kick[order] = rng.normal(0.0, kick_rms / np.sqrt(2.0), (n, 2))
    st.v[:n] += kick
    for _ in range(STEPS):
        sim.advance_one()
        assert sim.failure is None
    o = np.argsort(st.key[:n])
    return st.p[:n][o].copy()


def test_the_undrained_sound_speed_is_eq28():
    from psph.physics.material import soil_from_scene

    soil = soil_from_scene(block_scene())
    G = 12.5e6 / (2 * 1.33)
    assert soil.undrained_sound_speed == pytest.approx(
        np.sqrt((1e8 / 0.4 + 4 * G / 3) / (0.4 * 1000 + 0.6 * 2650)), rel=1e-12)
    assert soil.undrained_sound_speed / soil.sound_speed == pytest.approx(5.2, abs=0.05)


def test_viscosity_at_the_undrained_speed_damps_the_pressure_of_approaching_particles():
    left = {}
    for sound in ("solid", "undrained"):
        clean = _pressure_after_kick(sound, 0.0)
        kicked = _pressure_after_kick(sound, 0.5)
        left[sound] = float(np.sqrt(np.mean((kicked - clean) ** 2)))
    assert left["undrained"] < 0.6 * left["solid"], left

"""The projection's stable step (issue 39), pinned from both sides at the CI size.

The one-sweep step (`time.integrator = "euler"`) takes the effective stress and the
velocity both from step n: forward Euler for the skeleton's wave, which the projection's
implicit pore water does not hold. On the paper's column at 0.83 x Eq. (41) it ran for
0.3 s and then grew until the top row left the domain (exit 3 at 0.571 s); on the CI
column it grew at Eq. (41) after 0.4 s and, at half of it, during the undrained loading
(p at 27 q by 0.01 s). After the kick (symplectic) the skeleton is leapfrog and the
undrained mode damped: it runs at Eq. (41) to the end. So validation refuses the
one-sweep step with the projection, and the projection's default integrator is the
symplectic one. The whole map: bench/verification/projection_stability.py.
"""

import subprocess
import sys

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.physics.limits import solid_dt_limit
from tests.helpers import assert_bad_input

Q = 1.0e4
CI = ["particles.dx=0.02", "material.k=8e-4", "output.interval=0.0", "output.times=[]",
      "checkpoint.at_end=false"]
PROJECTION = ["pressure.scheme='projection'"]


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "psph", *args], capture_output=True,
                          text=True, timeout=120)


def _p_range(out) -> tuple[float, float]:
    h = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    return float(h["p_max"].max()), float(h["p_min"].min())


def test_the_issue_command_with_the_one_sweep_step_is_refused(tmp_path):
    """The issue's command with the one-sweep step named: exit 2, one line naming the
    key, the value, the rule and the stable step of the symplectic one, nothing written."""
    out = tmp_path / "out"
    r = _cli("run", "terzaghi_tpi", "--out", str(out), "--set", "pressure.scheme='projection'",
             "--set", "time.integrator='euler'", "--set", "time.dt=1.0e-5")
    assert_bad_input(r, ["time.integrator", "euler", "no stable step", "symplectic",
                         "Eq. (41) 1.200e-05 s"], out)


def test_the_projection_takes_the_symplectic_step_by_default():
    """Without `time.integrator` the projection kicks first; the other schemes keep the
    one-sweep step; a given integrator is kept."""
    assert load_scene("terzaghi_tpi", PROJECTION).time.integrator == "symplectic"
    assert load_scene("terzaghi_tpi").time.integrator == "euler"
    assert load_scene("terzaghi_tpi", ["pressure.scheme='explicit'", "time.dt=2e-7"]
                      ).time.integrator == "euler"
    assert load_scene("terzaghi_tpi", ["time.integrator='symplectic'"]).time.integrator \
        == "symplectic"
    forced = load_scene("terzaghi_tpi", PROJECTION + ["time.integrator='euler'",
                                                  "pressure.allow_unstable=true"])
    assert forced.time.integrator == "euler"


def test_the_projection_above_the_solid_cap_is_refused(tmp_path):
    """The accepted region ends at Eq. (41): 1 % above it is exit 2 naming the bound."""
    cap = solid_dt_limit(load_scene("terzaghi_tpi", CI + PROJECTION))
    assert load_scene("terzaghi_tpi", CI + PROJECTION + [f"time.dt={cap!r}"]).time.dt == cap
    out = tmp_path / "out"
    r = _cli("run", "terzaghi_tpi", "--out", str(out), *sum(
        (["--set", s] for s in CI + PROJECTION + [f"time.dt={1.01 * cap!r}"]), []))
    assert_bad_input(r, ["time.dt", "above the solid limit Eq. (41)", f"{cap:.3e}"], out)


@pytest.mark.slow
def test_the_symplectic_projection_at_the_solid_cap_runs_to_tv_1(tmp_path):
    """Inside the region: the default step (Eq. 41, 2.4e-5 s) runs the CI column to
    T_v = 1 with p bounded and within 1 % of q at every T_v (measured 2026-12-02)."""
    scene = load_scene("terzaghi_tpi", CI + PROJECTION + [
        "verification.tv=[0.05, 0.1, 0.2, 0.5, 1.0]", "pressure.tolerance=1e-6"])
    scene.time.dt = None  # the scene's TPI step off: the projection's default
    summary = run(scene, tmp_path, quiet=True)
    assert summary["dt"]["main_s"] == solid_dt_limit(scene)
    errors = summary["errors"]["pressure"]
    assert set(errors) == {"0.05", "0.1", "0.2", "0.5", "1"}
    assert all(e["max_abs_p_error_over_q"] < 0.01 for e in errors.values()), errors
    p_max, p_min = _p_range(tmp_path)
    assert p_max < 1.2 * Q and p_min > -0.1 * Q


@pytest.mark.slow
@pytest.mark.parametrize("share,grown_by", [(1.0, 0.5), (0.5, 0.012)])
def test_the_one_sweep_projection_grows_at_and_below_the_solid_cap(tmp_path, share,
                                                                   grown_by):
    """Why it is refused: forced, the one-sweep step at Eq. (41) grows after 0.4 s and at
    half of it during the undrained loading (the run still exits 0: p is bounded only
    by the particles staying in the box)."""
    cap = solid_dt_limit(load_scene("terzaghi_tpi", CI + PROJECTION))
    scene = load_scene("terzaghi_tpi", CI + PROJECTION + [
        "time.integrator='euler'", "pressure.allow_unstable=true", f"time.dt={share * cap!r}",
        f"time.end={grown_by}", "verification.tv=[]"])
    run(scene, tmp_path, quiet=True)
    p_max, p_min = _p_range(tmp_path)
    assert p_max > 1.2 * Q or p_min < -0.1 * Q, (p_max, p_min)


def test_history_is_written_when_a_run_fails(tmp_path):
    """A numerical failure (exit 3) leaves history.csv up to the failure, to see how it
    grew: TPI at the solid cap on the GeoTaichi column (R = 21) stops at about 15 ms."""
    out = tmp_path / "out"
    r = _cli("run", "terzaghi_undrained", "--out", str(out), "--quiet",
             "--set", "pressure.scheme='tpi'", "--set", "pressure.alpha=0.5",
             "--set", "time.integrator='euler'", "--set", "pressure.allow_unstable=true",
             "--set", "time.dt=2.4e-5", "--set", "time.end=0.05", "--set", "verification.tv=[]")
    assert r.returncode == 3, r.stderr
    h = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    t_fail = float(r.stderr.split("t = ")[1].split(" s")[0])
    assert len(h) > 3 and t_fail - 2e-3 < h["time"][-1] <= t_fail

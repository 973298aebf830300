"""Every kind of bad input: exit code 2, one line naming key / value / rule, nothing written."""

import subprocess
import sys
from pathlib import Path

import pytest

from psph.config.load import builtin_dir
from tests.helpers import assert_bad_input

TERZAGHI = (builtin_dir() / "terzaghi_tpi.toml").read_text()


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "psph", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=120)


CASES = [
    # (override or text edit, words the message must contain)
    (["--set", "material.colour=1"], ["unknown key", "material.colour"]),
    (["--set", "loads=[]"], ["verification.reference", "terzaghi", "on the top side"]),
    (["--set", "boundaries.bottom={motion='fixed', flow='drained', drained_from=0.02}"],
     ["verification.reference", "the same time", "0.01, 0.02"]),
    (["--set", "material.E='stiff'"], ["material.E", "'stiff'", "number"]),
    (["--set", "material.E=-2e7"], ["material.E", "-2", "greater than 0"]),
    (["--set", "material.K_l=0"], ["material.K_l", "0", "greater than 0"]),
    (["--set", "material.k=-1e-4"], ["material.k", "greater than or equal to 0"]),
    (["--set", "particles.dx=0"], ["particles.dx", "greater than 0"]),
    (["--set", "time.dt=-1e-6"], ["time.dt", "greater than 0"]),
    (["--set", "time.end=0"], ["time.end", "greater than 0"]),
    (["--set", "material.porosity=1.2"], ["material.porosity", "1.2", "less than 1"]),
    (["--set", "material.porosity=0"], ["material.porosity", "greater than 0"]),
    (["--set", "material.nu=0.5"], ["material.nu", "0.5", "less than 0.5"]),
    (["--set", "material.nu=-1.5"], ["material.nu", "greater than -1"]),
    (["--set", "particles.blocks.0.max=[0.1, 1.5]"], ["particles.blocks[0].max[1]", "1.5",
                                                      "outside the walls"]),
    (["--set", "pressure.alpha=1.5"], ["pressure.alpha", "1.5", "less than or equal to 1"]),
    (["--set", "pressure.alpha=-0.1"], ["pressure.alpha", "-0.1", "greater than or equal to 0"]),
    (["--set", "pressure.R=0"], ["pressure.R", "greater than 0"]),
    (["--set", "pressure.R=-3"], ["pressure.R", "-3", "greater than 0"]),
    (["--set", "pressure.beta=-0.04"], ["pressure.beta", "-0.04", "greater than or equal to 0"]),
    (["--set", "stabilisation.shepard_every=-5"], ["stabilisation.shepard_every", "-5"]),
    (["--set", "output.probes.A=[0.05, 2.0]"], ["output.probes.A", "2.0", "outside the domain"]),
    (["--set", "verification.reference='nope'"], ["verification.reference", "nope"]),
    (["--set", "time.dt=1e-4"], ["time.dt", "0.0001", "solid limit Eq. (41)"]),
    (["--set", "boundaries.top.motion='sticky'"], ["boundaries.top.motion", "sticky"]),
    (["--set", "material.model='drucker_prager'"], ["material.plasticity", "required"]),
    (["--set", "material.plasticity.phi=95.0"], ["material.plasticity.phi", "95",
                                                 "less than 90"]),
    (["--set", "material.plasticity.phi=30.0"], ["material.model", "drucker_prager"]),
    (["--set", "initial.k0=0.5"], ["initial.k0", "gravity"]),
    (["--set", "initial.k0=-0.5"], ["initial.k0", "greater than 0"]),
    (["--set", "checkpoint.every=-1"], ["checkpoint.every", "-1"]),
    (["--set", "decomposition.imbalance_threshold=0.9"],
     ["decomposition.imbalance_threshold", "0.9", "greater than 1"]),
    (["--set", "decomposition.rebalance_every=1.5"], ["decomposition.rebalance_every"]),
    (["--set", "pressure.scheme='explicit'"], ["time.dt", "undrained wave limit"]),
    (["--set", "material.C_k=-2.0"], ["material.C_k", "-2.0", "greater than or equal to 0"]),
    (["--set", "material.porosity_min=0.6"],
     ["material.porosity", "0.4", "must be above material.porosity_min = 0.6"]),
    (["--set", 'time.integrator="leapfrog"'], ["time.integrator", "leapfrog", "symplectic"]),
    (["--set", "pressure.ponding=1"], ["pressure.ponding", "1"]),
    (["--set", "pressure.alpha=0.8"], ["pressure.alpha", "0.8", "TPI is unstable", "0.75"]),
    # a new user's column (issue 14): k = 5e-5, the TPI step at the solid cap, G = 1.47.
    # With alpha = 0.7, the symplectic step and pressure.allow_unstable it ran into exit 3
    # (n > 1) 2 ms after the drained switch (README, "Stability of TPI under gravity")
    (["--set", "material.k=5e-5", "--set", "time.dt=1.2e-5", "--set", "pressure.alpha=0.5"],
     ["time.dt", "1.2e-05", "TPI gain G", "1.47", "5 (1 - alpha)^2, 3.6) = 1.25",
      "--no-gravity", "dt <= 1.019e-05 s"]),
    (["--set", "material.k=5e-5", "--set", "time.dt=1.2e-5", "--set", "pressure.R=17.7",
      "--set", "pressure.alpha=0.7"], ["time.dt", "TPI gain G", "= 0.45 "]),
    # TPI from t = 0 under the impervious loaded top blew up at 1.1 ms (the old throughput
    # bench's column)
    (["--set", "pressure.explicit_until=0.0"],
     ["pressure.explicit_until", "0.0", "TPI loading while no side is drained", "(0.01 s)"]),
    # the undrained start is the state of one step load (terzaghi ramps it over 0.01 s)
    (["--set", "initial.undrained_load=true"],
     ["initial.undrained_load", "True", "needs a step load over the whole side"]),
    # under gravity the bound is 1.15 (1 - alpha)
    (["--set", "gravity=[0.0, -9.81]", "--set", "material.k=1e-4", "--set", "time.dt=1e-5",
      "--set", "pressure.alpha=0.5"],
     ["time.dt", "TPI gain G = dt gamma_l / (rho k) = 0.613", "1.15 (1 - alpha) = 0.575"]),
]


@pytest.mark.parametrize("args,words", CASES, ids=[c[0][1] for c in CASES])
def test_bad_value_exit_2_one_line_nothing_written(tmp_path, args, words):
    out = tmp_path / "out"
    assert_bad_input(run_cli("run", "terzaghi_tpi", "--out", str(out), *args), words, out)


def test_tpi_bound_can_be_overridden_explicitly():
    """The TPI bound is a measured one: a scene may step past it on purpose (the
    stability benches do) with pressure.allow_unstable."""
    from psph.config.load import load_scene
    from psph.physics.limits import tpi_gain, tpi_gain_limit

    over = ["material.k=5e-5", "time.dt=1.2e-5", "pressure.allow_unstable=true"]
    scene = load_scene("terzaghi_tpi", over)
    assert tpi_gain(scene, scene.time.dt) > tpi_gain_limit(scene.pressure.alpha, False)


def test_missing_file(tmp_path):
    out = tmp_path / "out"
    r = run_cli("run", str(tmp_path / "nope.toml"), "--out", str(out))
    assert r.returncode == 2
    assert "nope.toml" in r.stderr and "no such file" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_output_directory_that_cannot_be_created_exit_2_one_line(tmp_path):
    """An --out under a regular file (issue 15): exit 2, one line naming the directory and
    the cause, before any work (it was exit 1 with a raw NotADirectoryError)."""
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    out = blocker / "out"
    r = run_cli("run", "terzaghi_tpi", "--out", str(out), "--set", "time.end=1e-4")
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert str(out) in lines[0] and "Not a directory" in lines[0]
    assert "Traceback" not in r.stderr and r.stdout == ""


def test_unreadable_toml(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(TERZAGHI.replace("dx = 0.01", "dx = = 0.01"))
    out = tmp_path / "out"
    r = run_cli("run", str(bad), "--out", str(out))
    assert r.returncode == 2
    assert "not valid TOML" in r.stderr and "line" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_missing_required_key(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text(TERZAGHI.replace("E = 20.0e6\n", ""))
    r = run_cli("validate", str(f))
    assert r.returncode == 2 and "material.E" in r.stderr and "required" in r.stderr


def test_existing_output_untouched_on_bad_input(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("keep")
    r = run_cli("run", "terzaghi_tpi", "--out", str(out), "--set", "material.E=0")
    assert r.returncode == 2
    assert (out / "summary.json").read_text() == "keep"
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]


def test_validate_prints_resolved_scene():
    r = run_cli("validate", "terzaghi_tpi")
    assert r.returncode == 0
    assert "end = " in r.stdout and "h_factor = 1.2" in r.stdout


def test_list_names_builtin_scenes():
    r = run_cli("list")
    assert r.returncode == 0
    names = [line.split()[0] for line in r.stdout.splitlines()]
    assert names == ["collapse_3d", "collapse_dry", "collapse_saturated_3d",
                     "collapse_saturated_psi-5",
                     "collapse_saturated_psi0",
                     "collapse_saturated_psi2.5", "cryer", "geostatic_column", "harmonic",
                     "retrogressive_k0_0.5", "retrogressive_k0_1.5", "slope_3d",
                     "slope_section",
                     "strip_footing", "terzaghi", "terzaghi_3d", "terzaghi_tpi",
                     "terzaghi_undrained"]


def test_set_override_reaches_resolved_scene(tmp_path):
    r = run_cli("validate", "terzaghi_tpi", "--set", "material.E=3e7")
    assert r.returncode == 0 and "E = 30000000.0" in r.stdout


def test_resolved_scene_reruns_identically(tmp_path):
    """OUT/scene.toml is a complete scene: validating it gives the same resolved scene."""
    first = run_cli("validate", "terzaghi_tpi").stdout
    f = Path(tmp_path) / "resolved.toml"
    f.write_text(first)
    assert run_cli("validate", str(f)).stdout == first

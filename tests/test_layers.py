"""Soil layers between ground profiles (issue 16, item 3): inline or CSV profiles, the
lattice points between them, and one clear line (exit 2) for a profile that is not
monotonic in x, a layer whose bottom is above its top, or a missing file."""

import subprocess
import sys

import numpy as np
import pytest

from psph.config.load import load_scene
from psph.physics.initial import soil_positions
from tests.helpers import assert_bad_input

SCENE = """
name = "section"
[domain]
min = [0.0, 0.0]
max = [20.0, 10.0]
[particles]
dx = 0.25
[[particles.layers]]
top = {top}
bottom = {bottom}
[material]
E = 1.0e7
nu = 0.3
porosity = 0.4
rho_s = 2650.0
k = 1.0e-6
K_l = 1.0e8
[boundaries]
bottom = {{ motion = "fixed" }}
[time]
end = 1e-3
"""
TOP = [[0.0, 8.0], [6.0, 8.0], [14.0, 4.0], [20.0, 4.0]]  # a slope from 8 m down to 4 m
BOTTOM = [[0.0, 1.0], [20.0, 3.0]]  # a dipping bedrock


def _toml(value) -> str:
    return f'"{value}"' if isinstance(value, str) else str(value)


def _scene(tmp_path, top, bottom):
    path = tmp_path / "section.toml"
    path.write_text(SCENE.format(top=_toml(top), bottom=_toml(bottom)))
    return path


def test_a_layer_holds_the_lattice_points_between_its_profiles(tmp_path):
    x = soil_positions(load_scene(str(_scene(tmp_path, TOP, BOTTOM))))
    zt = np.interp(x[:, 0], *np.array(TOP).T)
    zb = np.interp(x[:, 0], *np.array(BOTTOM).T)
    assert np.all((x[:, 1] >= zb - 1e-9) & (x[:, 1] <= zt + 1e-9))
    # every lattice point between the profiles is there (none missed, none twice)
    g = np.stack(np.meshgrid(np.arange(0.125, 20, 0.25), np.arange(0.125, 10, 0.25)),
                 axis=-1).reshape(-1, 2)
    between = (g[:, 1] >= np.interp(g[:, 0], *np.array(BOTTOM).T))
    between &= g[:, 1] <= np.interp(g[:, 0], *np.array(TOP).T)
    assert len(x) == between.sum() == len(np.unique(x, axis=0))
    # the section's area: 120 m^2 under the top, 40 under the bottom
    assert abs(len(x) * 0.25 ** 2 - 80.0) < 0.03 * 80.0


def test_a_csv_profile_gives_the_same_particles_as_inline_points(tmp_path):
    csv = tmp_path / "top.csv"
    csv.write_text("x,z  # survey of 2026\n" + "\n".join(f"{a},{b}" for a, b in TOP) + "\n")
    inline = soil_positions(load_scene(str(_scene(tmp_path, TOP, BOTTOM))))
    from_csv = soil_positions(load_scene(str(_scene(tmp_path, str(csv), BOTTOM))))
    assert np.array_equal(inline, from_csv)


def _run(path):
    return subprocess.run([sys.executable, "-m", "psph", "run", str(path), "--out",
                           str(path.parent / "out")], capture_output=True, text=True,
                          timeout=120)


@pytest.mark.parametrize("top, bottom, words", [
    ([[0.0, 8.0], [6.0, 8.0], [5.0, 7.0], [20.0, 4.0]], BOTTOM,
     ["particles.layers[0].top point 2", "not monotonic in x"]),
    (TOP, [[0.0, 1.0], [20.0, 6.0]], ["particles.layers[0].bottom", "above the top at x = 20"]),
    (TOP, "no_such_profile.csv", ["particles.layers[0].bottom", "no such file"]),
    (TOP, [[30.0, 1.0], [40.0, 1.0]], ["particles.layers[0].bottom", "no x range in common"]),
])
def test_bad_profiles_exit_2_with_one_line(tmp_path, top, bottom, words):
    path = _scene(tmp_path, top, bottom)
    assert_bad_input(_run(path), words, path.parent / "out")


def test_a_csv_row_that_is_not_two_numbers_names_its_line(tmp_path):
    csv = tmp_path / "top.csv"
    csv.write_text("x,z\n0,8\n6,eight\n20,4\n")
    r = _run(_scene(tmp_path, str(csv), BOTTOM))
    assert r.returncode == 2
    assert "line 3" in r.stderr and "not two numbers" in r.stderr


PHREATIC = [[0.0, 6.0], [10.0, 5.0], [20.0, 3.5]]  # below ground: 8 m at the left, 4 m right


@pytest.mark.parametrize("as_csv", [False, True])
def test_a_phreatic_profile_gives_hydrostatic_p_below_it_and_none_above(tmp_path, as_csv):
    """issue 16, item 4: p = rho_l g (z_w(x) - z) below the phreatic surface, 0 above."""
    from psph.physics.initial import initial_particles

    table = PHREATIC
    if as_csv:
        table = tmp_path / "phreatic.csv"
        table.write_text("x,z\n" + "\n".join(f"{a},{b}" for a, b in PHREATIC) + "\n")
        table = f'"{table}"'
    path = _scene(tmp_path, TOP, BOTTOM)
    path.write_text(path.read_text()
                    .replace('name = "section"', 'name = "section"\ngravity = [0.0, -9.81]')
                    .replace('[time]', f'[initial]\nk0 = 0.5\nwater_table = {table}\n[time]'))
    data = initial_particles(load_scene(str(path)))
    x = data["x"]
    z_w = np.interp(x[:, 0], *np.array(PHREATIC).T)
    expect = 1000.0 * 9.81 * np.maximum(z_w - x[:, 1], 0.0)
    assert np.allclose(data["p"], expect, rtol=1e-12, atol=1e-9)
    assert (x[:, 1] > z_w).sum() > 100 and (data["p"][x[:, 1] > z_w] == 0.0).all()


def test_a_phreatic_profile_not_monotonic_in_x_exit_2(tmp_path):
    path = _scene(tmp_path, TOP, BOTTOM)
    path.write_text(path.read_text().replace('name = "section"', 'name = "section"\n'
                    'gravity = [0.0, -9.81]').replace(
        '[time]', '[initial]\nwater_table = [[0.0, 6.0], [0.0, 5.0]]\n[time]'))
    r = _run(path)
    assert r.returncode == 2
    assert "initial.water_table point 1" in r.stderr and "not monotonic" in r.stderr


@pytest.mark.parametrize("table, words", [
    ("-1.0", ["initial.water_table = -1.0", "below the domain's floor"]),
    ("[[0.0, 6.0], [20.0, -1.0]]", ["initial.water_table at x = 20", "below the domain's floor"]),
    ("[[30.0, 6.0], [40.0, 5.0]]", ["initial.water_table", "no x in the domain"]),
])
def test_a_water_table_outside_the_domain_exit_2(tmp_path, table, words):
    """issue 16: a water table below the domain's floor or beside it is one line, exit 2,
    nothing written (above the top is ponded ground: allowed, tests/test_hydraulics.py)."""
    path = _scene(tmp_path, TOP, BOTTOM)
    path.write_text(path.read_text().replace('name = "section"', 'name = "section"\n'
                    'gravity = [0.0, -9.81]').replace(
        '[time]', f'[initial]\nwater_table = {table}\n[time]'))
    r = _run(path)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert all(w in r.stderr for w in words), r.stderr
    assert not (tmp_path / "out").exists()

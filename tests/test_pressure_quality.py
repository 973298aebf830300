"""Pressure quality (psph/verify/pressure.py): the hydrostatic pressure of the water table
at the current position, the checkerboard index, and the summary block (serial, fast)."""

import json
import math

import h5py
import numpy as np
import pytest

from psph.analysis.pressure import main
from psph.config.load import load_scene, to_toml
from psph.physics.initial import initial_particles
from psph.verify.pressure import (
    checkerboard_index,
    excess_pressure,
    hydrostatic_pressure,
    mean_effective_stress,
    neighbour_pairs,
    phreatic_excess,
    phreatic_level,
    pressure_quality,
    suction_integral,
)

DX = 0.1
H = 1.2 * DX
N = 30


def _lattice(n: int = N, dx: float = DX) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    g = (np.arange(n) + 0.5) * dx
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    x = np.c_[g[i.ravel()], g[j.ravel()]]
    return x, i.ravel(), j.ravel()


def _scene(water_table, dx: float = DX):
    """The geostatic column with spacing dx and the given `initial.water_table`."""
    scene = load_scene("geostatic_column", [f"particles.dx={dx}"])
    scene.initial.water_table = water_table
    return scene


def test_neighbour_pairs_match_brute_force():
    rng = np.random.default_rng(3)
    x = rng.uniform(0.0, 1.5, (400, 2))
    i, j, r = neighbour_pairs(x, 0.2)
    d = np.linalg.norm(x[:, None] - x[None], axis=2)
    bi, bj = np.nonzero((d < 0.2) & ~np.eye(len(x), dtype=bool))
    assert set(zip(i.tolist(), j.tolist(), strict=True)) == \
        set(zip(bi.tolist(), bj.tolist(), strict=True))
    assert np.allclose(r, d[i, j])


def test_checkerboard_index_linear_checkerboard_constant():
    x, i, j = _lattice()
    interior = np.all((x > 3 * H) & (x < N * DX - 3 * H), axis=1)
    linear = 4.0e3 + 2.0e3 * x[:, 0] - 9.81e3 * x[:, 1]
    assert checkerboard_index(x, linear, H, interior) < 0.05
    assert checkerboard_index(x, linear, H) < 0.05  # edges included: still small
    odd_even = (-1.0) ** (i + j)
    assert checkerboard_index(x, odd_even, H) > 1.0
    assert checkerboard_index(x, odd_even, H, interior) == pytest.approx(1.4547, abs=2e-3)
    # noise on top of a smooth field is seen in proportion to its share of the spread
    assert checkerboard_index(x, linear + 0.1 * linear.std() * odd_even, H) > 0.1
    assert checkerboard_index(x, np.full(len(x), 7.3), H) == 0.0
    assert checkerboard_index(x, np.zeros(len(x)), H) == 0.0


def test_hydrostatic_pressure_level_and_surface():
    x, _, _ = _lattice(10)  # 1 x 1 m block of particles, tops at y = 0.95 (centres)
    gamma = 1000.0 * 9.81
    level = hydrostatic_pressure(x, _scene(0.55))
    assert np.allclose(level, gamma * np.maximum(0.55 - x[:, 1], 0.0))
    surface = hydrostatic_pressure(x, _scene("surface"))
    assert np.allclose(surface, gamma * (0.95 - x[:, 1]))  # 0 at the top particle's centre
    # the surface is the current one: lower the right half by 0.3 m
    moved = x.copy()
    right = moved[:, 0] > 0.5
    moved[right, 1] -= 0.3
    p = hydrostatic_pressure(moved, _scene("surface"))
    assert np.allclose(p[right], gamma * (0.65 - moved[right, 1]))
    assert np.allclose(p[~right], gamma * (0.95 - moved[~right, 1]))
    # a level above the lowered surface follows the surface there (no water above soil)
    p = hydrostatic_pressure(moved, _scene(0.8))
    assert np.allclose(p[right], gamma * (0.65 - moved[right, 1]))
    assert np.allclose(p[~right], gamma * np.maximum(0.8 - moved[~right, 1], 0.0))
    assert np.all(hydrostatic_pressure(x, _scene(None)) == 0.0)
    assert np.allclose(hydrostatic_pressure(x, _scene("surface"), surface_y=2.0),
                       gamma * (2.0 - x[:, 1]))


def test_phreatic_excess_reads_drawdown_as_none_and_suction_as_itself():
    """A column drained through a free face holds p = 0 above its lowered phreatic line:
    over the ground surface's table that is negative excess, over the phreatic line none
    (the paper's Fig. 16 text). Hydrostatic from a lowered level: none. Suction (p < 0)
    stays excess, all of it; positive excess stays as it was."""
    x, _, _ = _lattice(10)  # tops at y = 0.95 (centres)
    gamma = 1000.0 * 9.81
    scene = _scene("surface")
    right = x[:, 0] > 0.5
    hydro = gamma * (0.95 - x[:, 1])

    def both(p):
        snap = {"x": x, "p": p}
        return excess_pressure(snap, scene), phreatic_excess(snap, scene)

    ex, ph = both(hydro)
    assert np.allclose(ex, 0.0) and np.allclose(ph, 0.0)
    drained = np.where(right, 0.0, hydro)
    ex, ph = both(drained)
    assert np.allclose(ex[right], -hydro[right]) and np.allclose(ph, 0.0)
    lowered = np.where(right, gamma * np.maximum(0.45 - x[:, 1], 0.0), hydro)
    ex, ph = both(lowered)
    assert ex[right].min() < -4e3 and np.allclose(ph, 0.0, atol=1e-9)
    suction = np.where(right, -5e3, hydro)
    ex, ph = both(suction)
    assert np.allclose(ph[right], -5e3) and np.allclose(ph[~right], 0.0)
    bump = hydro + np.where(right & (x[:, 1] < 0.3), 8e3, 0.0)  # a pressurised band
    ex, ph = both(bump)
    assert np.allclose(ph, ex)
    # below the threshold (gamma_l 2 dx): drained, the excess is p itself
    damp = np.where(right, 1.5 * gamma * DX, hydro)
    ex, ph = both(damp)
    assert np.allclose(ph[right], damp[right]) and ex[right].min() < -5e3
    # a numeric table: the line never rises above it, however high the heads above it
    level = _scene(0.55)
    hydro_55 = gamma * np.maximum(0.55 - x[:, 1], 0.0)
    above = x[:, 1] > 0.55
    snap = {"x": x, "p": np.where(above, 2.0 * gamma * 0.4, 0.0)}
    assert np.allclose(phreatic_excess(snap, level), snap["p"] - hydro_55)
    assert np.all(phreatic_level(x, snap["p"], level) <= 0.55)
    assert np.allclose(phreatic_excess({"x": x, "p": hydro_55}, level), 0.0)


def test_frames_draw_the_excess_over_the_phreatic_line_behind_a_drained_surface():
    """`psph plot`'s excess: behind a drained free surface (the collapses) the table is
    the current phreatic line, so a face drained to p = 0 shows none; with ponding (the
    slopes) the table is the ground surface, and the same drawdown shows as negative."""
    from psph.analysis.plot import excess_label, excess_of

    x, _, _ = _lattice(10)
    gamma = 1000.0 * 9.81
    right = x[:, 0] > 0.5
    snap = {"x": x, "p": np.where(right, 0.0, gamma * (0.95 - x[:, 1]))}
    for ponding, drawn in (("drained", 0.0), (True, None)):
        scene = _scene("surface")
        scene.pressure.ponding = ponding
        ex = excess_of(snap, scene)
        if drawn is None:
            assert np.allclose(ex, excess_pressure(snap, scene)) and ex[right].min() < -5e3
            assert excess_label(scene) == "excess p"
        else:
            assert np.allclose(ex, drawn)
            assert "phreatic" in excess_label(scene)


def test_suction_integral_sums_only_the_negative_pressure_over_the_areas():
    p = np.array([-2.0e3, 5.0e3, -1.0e3, 0.0])
    vol = np.array([0.01, 0.04, 0.02, 0.03])
    assert suction_integral({"p": p, "vol": vol}) == pytest.approx(2.0e3 * 0.01 + 1.0e3 * 0.02)
    assert suction_integral({"p": np.abs(p), "vol": vol}) == 0.0


def test_initial_state_has_no_excess():
    scene = load_scene("collapse_saturated_psi0", [])
    data = initial_particles(scene)
    snap = {"x": data["x"], "p": data["p"]}
    assert np.abs(excess_pressure(snap, scene)).max() < 1e-6


def _fake_snapshots():
    scene = _scene("surface")
    x, i, j = _lattice(12)
    snaps = []
    for k, t in enumerate((0.0, 0.5, 1.0)):
        u = np.zeros_like(x)
        u[x[:, 0] > 0.8, 0] = 0.8 * k  # the right part slides off: debris at t > 0
        xt = x + u
        p = hydrostatic_pressure(xt, scene) + 1e3 * k * (-1.0) ** (i + j)
        stress = np.zeros((len(x), 6))
        stress[:, :3] = -2e4 * (1.2 - x[:, 1:2])
        snaps.append({"id": np.arange(len(x)) + 100, "x": xt, "u": u, "p": p,
                      "stress": stress, "time": t, "step": k})
    return scene, snaps


def test_pressure_quality_is_finite_and_serialisable():
    scene, snaps = _fake_snapshots()
    q = pressure_quality(snaps, scene)
    text = json.dumps(q, allow_nan=False)  # plain JSON: no NaN, no numpy types
    assert json.loads(text) == q
    s, o = q["series"], q["over_run"]
    assert s["time_s"] == [0.0, 0.5, 1.0]
    assert s["debris_particles"][0] == 0 and s["debris_particles"][-1] > 0
    assert s["checkerboard_p_debris"][0] is None and s["checkerboard_p_debris"][-1] > 0.5
    assert s["checkerboard_p_eff_all"][-1] < 0.1  # p' is linear in y (edges: not 0)
    assert s["excess_p50_Pa"][0] == 0.0
    assert o["excess_min_Pa"] == pytest.approx(-2e3) and o["excess_max_Pa"] == pytest.approx(2e3)
    assert o["excess_max_id"] >= 100 and len(o["excess_max_x_m"]) == 2
    for v in (o["excess_p1_min_Pa"], o["abs_excess_p99_max_Pa"], o["checkerboard_p_all_max"]):
        assert math.isfinite(v)
    for k, snap in enumerate(snaps):  # the new keys are what they say
        assert s["suction_p99_Pa"][k] == pytest.approx(
            np.percentile(np.maximum(-snap["p"], 0.0), 99))
        assert s["abs_phreatic_excess_p99_Pa"][k] == pytest.approx(
            np.percentile(np.abs(phreatic_excess(snap, scene)), 99))
    assert o["suction_p99_max_Pa"] == max(s["suction_p99_Pa"]) > 0.0
    assert o["abs_phreatic_excess_p99_max_Pa"] == max(s["abs_phreatic_excess_p99_Pa"]) > 0.0
    assert mean_effective_stress(snaps[0]["stress"])[0] == pytest.approx(2e4 * (1.2 - 0.05))


def test_cli_writes_summary(tmp_path, capsys):
    """`python -m psph.analysis.pressure OUT --write` on a hand-made output directory adds
    metrics.pressure_quality and keeps the rest of summary.json; a missing one: exit 2."""
    scene, snaps = _fake_snapshots()
    out = tmp_path / "run"
    out.mkdir()
    (out / "scene.toml").write_text(to_toml(scene))
    (out / "summary.json").write_text(json.dumps({"scene": scene.name,
                                                  "metrics": {"collapse": {"runout_m": 1.0}}}))
    with h5py.File(out / "particles.h5", "w") as f:
        for s in snaps:
            g = f.create_group(f"snapshots/{s['step']:08d}")
            g.attrs["time"], g.attrs["step"] = s["time"], s["step"]
            for k in ("id", "x", "u", "p", "stress"):
                g[k] = s[k]
            g["eps_p"] = np.zeros(len(s["x"]))
    assert main([str(out), "--write"]) == 0
    line = capsys.readouterr().out.splitlines()[1]
    assert line.split()[0] == "run" and line.split()[3] == "2.0"  # max excess, kPa
    summary = json.loads((out / "summary.json").read_text())
    assert summary["metrics"]["collapse"] == {"runout_m": 1.0}
    assert summary["metrics"]["pressure_quality"]["over_run"]["excess_max_Pa"] == \
        pytest.approx(2e3)
    # --row: p along one elevation at the last snapshot, from the right end
    assert main([str(out), "--where", "--row", "0.55", "--every", "1"]) == 0
    rows = capsys.readouterr().out.splitlines()
    assert "top 1 %" in rows[2] and "y = 0.55 m" in rows[3]
    profile = np.array([[float(v) for v in r.split()] for r in rows[4:]])
    assert len(profile) == 12 and np.all(np.diff(profile[:, 0]) < 0)  # the 12 of the row
    assert np.allclose(profile[:, 2], 9.81 * 0.6, atol=0.01)  # 1.15 - 0.55 m of water, kPa
    assert main([str(tmp_path / "missing")]) == 2
    assert "error" in capsys.readouterr().err

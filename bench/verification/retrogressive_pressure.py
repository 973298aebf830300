"""Pore pressure through the retrogressive failure (Section 4.5, Fig. 20 and 24) from
finished runs.

    python bench/verification/retrogressive_pressure.py bench/out/field_retrogressive_k0_0.5 \
        bench/out/field_retrogressive_k0_1.5
    python bench/verification/retrogressive_pressure.py --quick
        # retrogressive_k0_0.5 at dx = 2 m, 0.02 s of loading, to 0.02 s; checked

For each run directory:

- the median excess p (psph/verify/pressure.py) in the basal shear zone of the first
  slide: particles with eps_p > 0.05 that started in the bottom 4 m and in front of the
  first slide's back scarp, at the snapshot that first shows the slide;
- the most negative and the largest p over all snapshots (with time and position),
  against -0.5 MPa and the slope's initial total vertical stress at its base,
  rho_sat g H (pore pressure above it would be a negative effective vertical stress);
- the excess p of the debris (moved more than 5 dx) after each slide: its median and 95th
  percentile at the slide and just before the next one (or at the end), and the same
  statistics later over the particles that were debris at the slide (the debris grows
  between slides with freshly sheared soil, whose excess is new, not undissipated):
  Fig. 20 shows it dissipating; with the same particles' median mean effective stress
  p' (compression positive) at the slide and later, whose rise is the consolidation of
  Fig. 21 (negative: effective tension); and their median buoyant
  overburden gamma' (y_s - y) (y_s: the ground surface above, gamma' = (1 - n0)
  (rho_s - rho_l) |g|) with the median ratio r_u = excess / buoyant overburden: a
  liquefied soil at rest loaded without drainage keeps r_u = 1 while its excess grows
  with the overburden, so the pair tells a change of load from a change of r_u (a
  proxy: gamma' from the initial n, y_s the highest particle within about 2 dx);
- the maximum of p in history.csv (a row per 1 ms, 2-3 steps) against the same bar: rows
  above it, the largest, and the steps between the sharp falls of the maximum (by more
  than 20 %) while it is above the bar, beside the scene's Shepard interval
  `stabilisation.shepard_every` (equal: the maximum falls at the filter's passes);
- where the largest p of each snapshot sits: its height above the base, its p' and its
  lead over the mean p of the particles within 1 m, beside the median lead of every
  particle of the bottom row (y < 0.75 dx; its neighbours all sit higher, at less
  overburden, so its lead is positive without any spike).

Prints a table and writes <out>/retrogressive_pressure.json.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scene_runs import run_scene as start_run

from psph.config.load import run_scene
from psph.io.snapshots import read_snapshots
from psph.verify.collapse import slide_history
from psph.verify.pressure import DEBRIS_DX, excess_pressure, ground_surface, mean_effective_stress

ROOT = Path(__file__).resolve().parents[2]

BAND_EPS = 0.05  # equivalent plastic strain of the shear zone
BASE_ZONE_M = 4.0  # the basal shear zone starts in the bottom 4 m
RU_MIN_DEPTH_DX = 2.0  # r_u only below 2 dx of soil (near the surface it is 0 / 0)


def _median_p95(ex: np.ndarray) -> dict:
    return {"median_Pa": float(np.median(ex)) if len(ex) else None,
            "p95_Pa": float(np.percentile(ex, 95)) if len(ex) else None}


def _overburden(x: np.ndarray, ex: np.ndarray, sel: np.ndarray, gamma_b: float,
                dx: float) -> dict:
    """Median buoyant overburden gamma_b (y_s - y) of the selected particles (y_s:
    `ground_surface`), and the median r_u = excess / that overburden over those below
    RU_MIN_DEPTH_DX of soil."""
    depth = ground_surface(x, dx)[sel] - x[sel, 1]
    deep = depth > RU_MIN_DEPTH_DX * dx
    return {"buoyant_overburden_median_Pa": float(np.median(gamma_b * depth))
            if sel.any() else None,
            "ru_median": float(np.median(ex[sel][deep] / (gamma_b * depth[deep])))
            if deep.any() else None}


def history_maximum(out: Path, bar: float) -> dict:
    """history.csv's p_max (a row per history output, not every step) against `bar`: rows
    above it, the largest (with its time), and the median step count between the falls
    of p_max by more than 20 % from one row to the next among the rows above the bar
    (None without two such falls)."""
    h = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    p, step = h["p_max"], h["step"]
    above = p > bar
    falls = np.flatnonzero(above[:-1] & (p[1:] < 0.8 * p[:-1])) + 1
    gaps = np.diff(step[falls])
    k = int(np.argmax(p))
    return {"rows": int(len(p)), "rows_above": int(above.sum()), "max_Pa": float(p[k]),
            "max_time_s": float(h["time"][k]),
            "steps_between_falls": float(np.median(gaps)) if len(gaps) else None}


def _lead(x: np.ndarray, p: np.ndarray, i: np.ndarray, radius: float = 1.0) -> np.ndarray:
    """p[i] minus the mean p of the other particles within `radius` of each i (nan with
    none), over the particles sorted by x."""
    order = np.argsort(x[:, 0])
    xs = x[order, 0]
    out = np.full(len(i), np.nan)
    for k, j in enumerate(i):
        lo, hi = np.searchsorted(xs, [x[j, 0] - radius, x[j, 0] + radius])
        cand = order[lo:hi]
        d = np.linalg.norm(x[cand] - x[j], axis=1)
        near = cand[(d < radius) & (cand != j)]
        if len(near):
            out[k] = p[j] - p[near].mean()
    return out


def largest_p_sites(snaps: list[dict], dx: float) -> dict:
    """Per snapshot after the first, the particle of the largest p: height (the base is
    y = 0 in the slopes), p' (compression positive) and its lead (`_lead`); and the median
    lead of the bottom row (y < 0.75 dx) in each snapshot, the lead without a spike."""
    sites, row = [], []
    for s in snaps[1:]:
        x, p = s["x"], s["p"]
        i = int(np.argmax(p))
        lead = _lead(x, p, np.array([i]))[0]
        sites.append({"time_s": float(s["time"]), "id": int(s["id"][i]), "p_Pa": float(p[i]),
                      "height_m": float(x[i, 1]),
                      "p_eff_Pa": float(mean_effective_stress(s["stress"][i:i + 1])[0]),
                      "lead_Pa": None if np.isnan(lead) else float(lead)})
        bottom = _lead(x, p, np.flatnonzero(x[:, 1] < 0.75 * dx))
        if np.isfinite(bottom).any():
            row.append(float(np.nanmedian(bottom)))
    return {"sites": sites, "bottom_row_lead_median_Pa": row}


def run_checks(out: Path) -> dict:
    scene = run_scene(out)
    snaps = read_snapshots(out / "particles.h5")
    dx = scene.particles.dx
    slides = slide_history(snaps, dx)
    times = np.array([s["time"] for s in snaps])
    m = scene.material
    rho_sat = (1 - m.porosity) * m.rho_s + m.porosity * m.rho_l
    x0 = snaps[0]["x"] - snaps[0]["u"]
    height = float(x0[:, 1].max() + 0.5 * dx)
    sigma_v_base = rho_sat * abs(scene.gravity[1]) * height
    result = {"run": str(out), "t_end_s": float(times[-1]), "slides": slides["slides"],
              "slide_times_s": slides["slide_times_s"],
              "sigma_v_base_Pa": sigma_v_base, "dx_m": dx,
              "history": history_maximum(out, sigma_v_base),
              "shepard_every": scene.stabilisation.shepard_every,
              "largest_p": largest_p_sites(snaps, dx)}
    # basal shear zone of the first slide
    if slides["slides"]:
        t1 = slides["slide_times_s"][0]
        scarp1 = slides["slide_scarps_m"][0]
        s = snaps[int(np.argmin(np.abs(times - t1)))]
        start = s["x"] - s["u"]
        zone = (s["eps_p"] > BAND_EPS) & (start[:, 1] < BASE_ZONE_M) & (start[:, 0] > scarp1)
        ex = excess_pressure(s, scene)
        result["first_slide"] = {"time_s": float(s["time"]), "back_scarp_m": scarp1,
                                 "zone_particles": int(zone.sum()),
                                 "zone_excess_median_Pa": float(np.median(ex[zone]))
                                 if zone.any() else None}
    # extremes of p over the snapshots
    lo = min(((float(s["p"].min()), s) for s in snaps), key=lambda a: a[0])
    hi = max(((float(s["p"].max()), s) for s in snaps), key=lambda a: a[0])
    result["p_min_Pa"] = lo[0]
    result["p_min_at"] = {"time_s": float(lo[1]["time"]),
                          "x_m": lo[1]["x"][int(np.argmin(lo[1]["p"]))].tolist()}
    result["p_max_Pa"] = hi[0]
    result["p_max_at"] = {"time_s": float(hi[1]["time"]),
                          "x_m": hi[1]["x"][int(np.argmax(hi[1]["p"]))].tolist()}
    result["p_above_sigma_v_base"] = int(sum((s["p"] > sigma_v_base).sum() for s in snaps))
    gamma_b = (1 - m.porosity) * (m.rho_s - m.rho_l) * abs(scene.gravity[1])
    # debris excess after each slide
    marks = list(slides["slide_times_s"]) + [float(times[-1]) + 1.0]
    decay = []
    for k, t in enumerate(marks[:-1]):
        t_next = min(marks[k + 1] - 1.0, float(times[-1]))
        stats = []
        for which, tt in enumerate((t, t_next)):
            s = snaps[int(np.argmin(np.abs(times - tt)))]
            debris = np.linalg.norm(s["u"], axis=1) > DEBRIS_DX * dx
            ex = excess_pressure(s, scene)
            stats.append({"time_s": float(s["time"]), "particles": int(debris.sum()),
                          **_median_p95(ex[debris])})
            if which == 0:
                ids_at = s["id"][debris]
            # the same particles later: their own dissipation, without the freshly
            # sheared soil that joined the debris since
            same = np.isin(s["id"], ids_at)
            stats[-1]["same_particles"] = {
                **_median_p95(ex[same]),
                "mean_effective_median_Pa": float(np.median(
                    mean_effective_stress(s["stress"][same]))) if same.any() else None,
                **_overburden(s["x"], ex, same, gamma_b, dx)}
        decay.append({"slide": k + 1, "at": stats[0], "later": stats[1]})
    result["debris_after_slides"] = decay
    return result


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="*", type=Path, help="finished runs' output directories")
    ap.add_argument("--quick", action="store_true",
                    help="run retrogressive_k0_0.5 at dx = 2 m, 0.02 s of gravity loading, to "
                         "0.02 s into <out> first, "
                         "and check it (a smoke check)")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "out",
                    help="directory of retrogressive_pressure.json (default bench/out)")
    args = ap.parse_args(argv)
    if args.quick:
        run = args.out / "retrogressive_pressure-run"
        start_run(run, "retrogressive_k0_0.5", 1,
                  ["particles.dx=2.0", "initial.equilibrate=0.02", "time.end=0.02",
                   "output.interval=0.01"], False)
        args.runs.append(run)
    if not args.runs:
        ap.error("no run directory given (or --quick)")
    rows = [run_checks(a) for a in args.runs]
    for r in rows:
        print(f"{r['run']}: t_end {r['t_end_s']:.1f} s, {r['slides']} slides at "
              f"{', '.join(f'{t:.0f}' for t in r['slide_times_s'])} s")
        fs = r.get("first_slide")
        if fs:
            med = fs["zone_excess_median_Pa"]
            print(f"  basal shear zone of the first slide (t = {fs['time_s']:.1f} s, "
                  f"{fs['zone_particles']} particles): median excess "
                  f"{'-' if med is None else f'{med / 1e3:+.1f}'} kPa")
        print(f"  p over all snapshots: min {r['p_min_Pa'] / 1e6:+.3f} MPa at "
              f"t = {r['p_min_at']['time_s']:.1f} s (bar -0.5 MPa), max "
              f"{r['p_max_Pa'] / 1e3:.0f} kPa at t = {r['p_max_at']['time_s']:.1f} s "
              f"(bar: sigma_v at the base {r['sigma_v_base_Pa'] / 1e3:.0f} kPa; "
              f"{r['p_above_sigma_v_base']} particle-snapshots above it)")
        h = r["history"]
        falls = h["steps_between_falls"]
        print(f"  history.csv (a row per 1 ms): max {h['max_Pa'] / 1e3:.0f} kPa at "
              f"t = {h['max_time_s']:.1f} s, {h['rows_above']} of {h['rows']} rows above "
              "the bar; " + (f"above it the maximum falls every {falls:.0f} steps"
                             if falls is not None else "no repeated falls above it")
              + f" (Shepard every {r['shepard_every']})")
        sites = r["largest_p"]["sites"]
        leads = [q["lead_Pa"] for q in sites if q["lead_Pa"] is not None]
        row = r["largest_p"]["bottom_row_lead_median_Pa"]
        if sites and leads and row:
            low = [q for q in sites if q["height_m"] < 0.75 * r["dx_m"]]
            print(f"  largest p of a snapshot: in the bottom row (y < 0.75 dx) in {len(low)} "
                  f"of {len(sites)} snapshots, lowest at y = "
                  f"{min(q['height_m'] for q in sites):.2f} m; its p' median "
                  f"{np.median([q['p_eff_Pa'] for q in sites]) / 1e3:.1f} kPa; its lead over "
                  f"the mean p within 1 m median {np.median(leads) / 1e3:.0f} kPa (the "
                  f"bottom row's own lead: median {np.median(row) / 1e3:.0f} kPa)")
        print(f"  {'slide':>5s} {'t (s)':>6s} {'debris':>6s} {'median':>8s} {'p95':>8s}   "
              f"{'later t':>7s} {'median':>8s} {'p95':>8s}   {'same':>8s} {'same':>8s}"
              f"   {'pe_at':>8s} {'pe_later':>8s}   {'ob_at':>8s} {'ob_later':>8s}"
              f" {'ru_at':>5s} {'ru_later':>8s}"
              "  (excess p of the debris, kPa; 'same': the particles of the debris at the "
              "slide, later; pe: their median p' at the slide and later, kPa; ob: their "
              "median buoyant overburden, kPa; ru: their median excess / it)")
        for d in r["debris_after_slides"]:
            a, b = d["at"], d["later"]

            def f(v):
                return "-" if v is None else f"{v / 1e3:8.1f}"

            def fmt_ru(v):
                return "-" if v is None else f"{v:5.2f}"
            print(f"  {d['slide']:5d} {a['time_s']:6.1f} {a['particles']:6d} "
                  f"{f(a['median_Pa']):>8s} {f(a['p95_Pa']):>8s}   {b['time_s']:7.1f} "
                  f"{f(b['median_Pa']):>8s} {f(b['p95_Pa']):>8s}   "
                  f"{f(b['same_particles']['median_Pa']):>8s} "
                  f"{f(b['same_particles']['p95_Pa']):>8s}   "
                  f"{f(a['same_particles']['mean_effective_median_Pa']):>8s} "
                  f"{f(b['same_particles']['mean_effective_median_Pa']):>8s}   "
                  f"{f(a['same_particles']['buoyant_overburden_median_Pa']):>8s} "
                  f"{f(b['same_particles']['buoyant_overburden_median_Pa']):>8s} "
                  f"{fmt_ru(a['same_particles']['ru_median']):>5s} "
                  f"{fmt_ru(b['same_particles']['ru_median']):>8s}")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "retrogressive_pressure.json").write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

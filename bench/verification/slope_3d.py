"""`slope_3d`: the 3D retrogressive slope, and its plane-strain check.

    python bench/verification/slope_3d.py --check          # plane-strain check (~15 min)
    python bench/verification/slope_3d.py --full --end 10  # slope_3d's first 10 s (~45 min)
    python bench/verification/slope_3d.py --check --full --reuse   # tables finished runs
    python bench/verification/slope_3d.py --quick          # the check's first 2 ms

The plane-strain check: `slope_3d` with the toe cut over the whole width (the domain 5 dx
wide between its two slip walls, the cut polygon spans it) against the 2D scene
`retrogressive_k0_0.5` at the same dx (1 m) and dt (1e-3 s), both to `--check-end`
(default 12 s). The bar: the first two slides at the same time within one
snapshot interval (1 s) and the run-out within 5 % (at the second slide's snapshot and at
the end). The 2D run is on one rank, the 3D ones under `mpirun -n NP` (default 2).

The full run: `slope_3d` to `--end` s, its metrics at each slide (retrogression along the
centre line, the scarp's width across the valley), the debris' footprint and volume, and
its wall time, with the pictures of `psph plot` copied beside the table.

Runs go to runs/slope_3d/<name> (`--runs`; `--reuse` keeps a finished one). Prints the
tables, writes <out>/slope_3d.json and .png (back scarp and run-out against time: 2D line,
3D markers; the full run's retrogression and scarp width).
"""

import argparse
import json
import platform
import subprocess
import sys
from datetime import date
from pathlib import Path

from scene_runs import run_scene

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "bench" / "out"
RUNS = ROOT / "runs" / "slope_3d"
DX, DT = 1.0, 1.0e-3
RUNOUT_BAR = 0.05
SLAB = [f"domain.max=[1000.0, {5 * DX}, 40.0]",
        f"remove.0.polygon=[[160.0, 0.0], [200.0, 0.0], [200.0, {5 * DX}], [160.0, {5 * DX}]]",
        "boundaries.front.symmetry=false"]


def run(out: Path, scene: str, ranks: int, settings: list[str], reuse: bool) -> dict:
    return run_scene(out, scene, ranks, settings, reuse)


def slides(s: dict) -> dict:
    m = s["metrics"]["collapse"]
    return {"slide_times_s": m["slide_times_s"], "slide_scarps_m": m["slide_scarps_m"],
            "series": {k: m["series"][k] for k in ("time_s", "runout_m", "back_scarp_m")},
            "runout_m": m["runout_m"], "particles": s["particles"], "ranks": s["ranks"],
            "wall_time_s": s["wall_time_s"]}


def runout_at(r: dict, t: float) -> float:
    times = r["series"]["time_s"]
    k = min(range(len(times)), key=lambda i: abs(times[i] - t))
    return r["series"]["runout_m"][k]


def plane_strain_check(end: float, ranks: int, reuse: bool, runs: Path = RUNS,
                       extra: tuple[str, ...] = ()) -> dict:
    s2 = run(runs / "plane_strain_2d", "retrogressive_k0_0.5", 1,
             [f"particles.dx={DX}", f"time.dt={DT}", f"time.end={end}", *extra], reuse)
    s3 = run(runs / "plane_strain_3d", "slope_3d", ranks, SLAB + [f"time.end={end}", *extra],
             reuse)
    r2, r3 = slides(s2), slides(s3)
    interval = 1.0  # both scenes' output.interval
    rows = []
    for k in range(2):
        t2 = r2["slide_times_s"][k] if k < len(r2["slide_times_s"]) else None
        t3 = r3["slide_times_s"][k] if k < len(r3["slide_times_s"]) else None
        rows.append({"slide": k + 1, "time_2d_s": t2, "time_3d_s": t3,
                     "time_ok": t2 is not None and t3 is not None
                     and abs(t3 - t2) <= interval + 1e-9})
    checks = []
    for label, t in (("second slide", rows[1]["time_2d_s"]), ("end", end)):
        if t is None:
            continue
        a, b = runout_at(r2, t), runout_at(r3, t)
        checks.append({"at": label, "time_s": t, "runout_2d_m": a, "runout_3d_m": b,
                       "rel": b / a - 1.0, "ok": abs(b / a - 1.0) <= RUNOUT_BAR})
    met = all(r["time_ok"] for r in rows) and bool(checks) and all(c["ok"] for c in checks)
    print(f"\nplane-strain check (dx = {DX} m, dt = {DT} s, to {end} s): 2D "
          f"{r2['particles']} particles, 3D slab {r3['particles']}")
    print(f"{'slide':>5s} {'t 2D (s)':>9s} {'t 3D (s)':>9s} {'within 1 s':>10s}")
    for r in rows:
        print(f"{r['slide']:5d} {_num(r['time_2d_s']):>9s} {_num(r['time_3d_s']):>9s} "
              f"{'yes' if r['time_ok'] else 'NO':>10s}")
    print(f"{'run-out at':>14s} {'2D (m)':>8s} {'3D (m)':>8s} {'diff':>7s} {'within 5 %':>10s}")
    for c in checks:
        print(f"{c['at'] + ' ' + format(c['time_s'], 'g') + ' s':>14s} {c['runout_2d_m']:8.2f} "
              f"{c['runout_3d_m']:8.2f} {100 * c['rel']:+6.1f}% {'yes' if c['ok'] else 'NO':>10s}")
    print("met" if met else "NOT met")
    return {"end_s": end, "2d": r2, "3d": r3, "slides": rows, "runout": checks, "met": met}


def full_run(end: float, ranks: int, reuse: bool, runs: Path = RUNS) -> dict:
    out = runs / f"full_{end:g}s"
    s = run(out, "slope_3d", ranks, [f"time.end={end}"], reuse)
    m = s["metrics"]
    plan, col = m["slope_3d"], m["collapse"]
    subprocess.run([sys.executable, "-m", "psph", "plot", str(out)], cwd=ROOT, check=True,
                   capture_output=True)
    print(f"\nslope_3d to {end:g} s: {s['particles']} particles on {s['ranks']} ranks, "
          f"{s['wall_time_s']:.0f} s wall ({s['wall_time_s'] / 60:.1f} min), "
          f"{s['steps']} steps")
    print(f"{'slide':>5s} {'t (s)':>6s} {'retrogression (m)':>18s} {'scarp width (m)':>16s}")
    for k, r in enumerate(plan["at_slides"]):
        print(f"{k + 1:5d} {r['time_s']:6.1f} {r['retrogression_m']:18.1f} "
              f"{r['scarp_width_m']:16.1f}")
    print(f"at {m['time_s']:.3g} s: run-out {col['runout_m']:.1f} m (centre line), "
          f"retrogression {plan['retrogression_m']:.1f} m, scarp width "
          f"{plan['scarp_width_m']:.1f} m, debris footprint {plan['footprint_area_m2']:.0f} m2, "
          f"volume {plan['debris_volume_m3']:.0f} m3 (the valley's: a half model mirrored)")
    return {"end_s": end, "particles": s["particles"], "ranks": s["ranks"],
            "wall_time_s": s["wall_time_s"], "steps": s["steps"], "out": str(out),
            "collapse": {k: v for k, v in col.items() if k != "series"},
            "slope_3d": plan, "series": col["series"]}


def _num(v) -> str:
    return "-" if v is None else f"{v:.1f}"


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    if "plane_strain" in result:
        ps = result["plane_strain"]
        for dim, style in (("2d", "-"), ("3d", "o")):
            sr = ps[dim]["series"]
            ax1.plot(sr["time_s"], sr["back_scarp_m"], style, color="C0", mfc="none",
                     label=f"back scarp, {dim.upper()}")
            ax1.plot(sr["time_s"], sr["runout_m"], style, color="C1", mfc="none",
                     label=f"run-out, {dim.upper()}")
        ax1.set(xlabel="t (s)", ylabel="m", title="plane-strain check: 2D line, 3D slab markers")
        ax1.legend(fontsize=7)
    if "full" in result:
        sr = result["full"]["slope_3d"]["series"]
        ax2.plot(sr["time_s"], sr["retrogression_m"], "o-", label="retrogression (centre line)")
        ax2.plot(sr["time_s"], sr["scarp_width_m"], "s-", label="scarp width (valley)")
        ax2.plot(result["full"]["series"]["time_s"], result["full"]["series"]["runout_m"],
                 "^-", label="run-out (centre line)")
        ax2.set(xlabel="t (s)", ylabel="m", title="slope_3d")
        ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="the plane-strain check")
    ap.add_argument("--check-end", type=float, default=12.0)
    ap.add_argument("--full", action="store_true", help="slope_3d itself")
    ap.add_argument("--end", type=float, default=10.0, help="the full run's end (s)")
    ap.add_argument("--np", type=int, default=2, help="ranks of the 3D runs")
    ap.add_argument("--reuse", action="store_true", help="keep finished runs")
    ap.add_argument("--runs", type=Path, default=RUNS,
                    help="directory of the runs (default runs/slope_3d)")
    ap.add_argument("--quick", action="store_true",
                    help="the plane-strain check's first 2 ms after 2 ms of gravity loading, "
                         "runs under <out> (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of slope_3d.json and .png (default bench/out)")
    args = ap.parse_args()
    if args.quick:
        args.check, args.check_end = True, 2.0e-3
        if args.runs == RUNS:
            args.runs = args.out / "slope_3d-runs"
    if not (args.check or args.full):
        ap.error("give --check, --full or both")
    result = {"date": date.today().isoformat(), "machine": platform.platform()}
    if args.check:
        result["plane_strain"] = plane_strain_check(
            args.check_end, args.np, args.reuse, args.runs,
            ("initial.equilibrate=0.002",) if args.quick else ())
    if args.full:
        result["full"] = full_run(args.end, args.np, args.reuse, args.runs)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "slope_3d.json").write_text(json.dumps(result, indent=1) + "\n")
    plot(result, args.out / "slope_3d.png")
    print(f"wrote {args.out / 'slope_3d.json'} and .png")


if __name__ == "__main__":
    main()

"""Run-out and back scarp against time of finished slope runs, side by side:
`metrics.collapse.series` and the slides of each run's `summary.json`.

    python bench/verification/slope_series.py OUT1 OUT2 ... [--every 5] [--png PATH]
    python bench/verification/slope_series.py --quick
        # retrogressive_k0_0.5 at dx = 2 m, 0.02 s of loading, to 0.02 s; tabled

Prints the table (the snapshot times every `--every` seconds that all runs reached, and
each run's slide times), draws run-out and back scarp against time (default
<out>/slope_series.png) and writes the table beside the PNG (.json).
"""

import argparse
import json
import sys
from pathlib import Path

from scene_runs import run_scene as start_run


def load(out: Path) -> dict:
    s = json.loads((out / "summary.json").read_text())
    c = s["metrics"]["collapse"]
    return {"name": out.name, "series": c["series"], "slides": c.get("slide_times_s", []),
            "end": s["end_time_s"], "particles": s["particles"]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="*", type=Path, help="finished runs' output directories")
    ap.add_argument("--every", type=float, default=5.0, help="table rows every ... s")
    ap.add_argument("--quick", action="store_true",
                    help="run retrogressive_k0_0.5 at dx = 2 m, 0.02 s of gravity loading, to "
                         "0.02 s into <out> first, "
                         "and table it every 0.01 s (a smoke check)")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "out",
                    help="directory of slope_series.png and .json (default bench/out)")
    ap.add_argument("--png", type=Path, help="the picture's path (default <out>/slope_series.png)")
    args = ap.parse_args(argv)
    args.png = args.png or args.out / "slope_series.png"
    if args.quick:
        run = args.out / "slope_series-run"
        start_run(run, "retrogressive_k0_0.5", 1,
                  ["particles.dx=2.0", "initial.equilibrate=0.02", "time.end=0.02",
                   "output.interval=0.01"], False)
        args.runs.append(run)
        args.every = 0.01
    if not args.runs:
        ap.error("no run directory given (or --quick)")
    runs = [load(r) for r in args.runs]
    end = min(r["end"] for r in runs)
    print("t (s)  " + "  ".join(f"{r['name'][-28:]:>28}" for r in runs))
    print("       " + "  ".join(f"{'run-out':>13} {'scarp':>14}" for _ in runs))
    t = args.every
    table = []
    while t <= end + 1e-6:
        cells, row = [], {"time_s": t}
        for r in runs:
            times = r["series"]["time_s"]
            k = min(range(len(times)), key=lambda i: abs(times[i] - t))
            runout, scarp = r["series"]["runout_m"][k], r["series"]["back_scarp_m"][k]
            cells.append(f"{runout:11.1f} m {scarp:12.1f} m")
            row[r["name"]] = {"runout_m": runout, "back_scarp_m": scarp}
        print(f"{t:5.1f}  " + "  ".join(cells))
        table.append(row)
        t += args.every
    for r in runs:
        print(f"{r['name']}: {r['particles']} particles, to {r['end']:.1f} s, slides at "
              + ", ".join(f"{s:.1f}" for s in r["slides"]) + " s")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for r in runs:
        ax[0].plot(r["series"]["time_s"], r["series"]["runout_m"], label=r["name"])
        ax[1].plot(r["series"]["time_s"], r["series"]["back_scarp_m"])
    ax[0].set(xlabel="t (s)", ylabel="run-out (m)")
    ax[1].set(xlabel="t (s)", ylabel="back scarp x (m)")
    ax[0].legend(fontsize=7)
    fig.tight_layout()
    args.png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.png, dpi=110)
    data = args.png.with_suffix(".json")
    data.write_text(json.dumps({"table": table, "slides": {r["name"]: r["slides"]
                                                           for r in runs}}, indent=1) + "\n")
    print(f"wrote {args.png} and {data}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The saturated-collapse table (Section 4.4, Table 1) from finished runs.

    make scene-collapse_saturated_psi-5 scene-collapse_saturated_psi0 \
         scene-collapse_saturated_psi2.5
    python bench/verification/collapse_table.py            # reads runs/collapse_saturated_*
    python bench/verification/collapse_table.py --quick    # psi = 0 at dx 0.16 m to 20 ms

For each dilatancy angle: the run-out at 0.6 s and at the end, the largest and the most
negative excess pore pressure over all snapshots and the highest 99th percentile of
|excess| (excess: p minus the hydrostatic pressure of the water table at the particle's
current position, psph/verify/pressure.py), the median excess in the shear band
(eps_p > 0.05) at the end, the checkerboard index of p' in the debris
at the end, and the back scarp at the end; then the same pressures over the current
phreatic line (`phreatic_excess`: drawdown through the drained face not read as negative
excess) and the suction max(-p, 0). Writes <out>/collapse_table.json.
"""

import argparse
import json
from pathlib import Path

import numpy as np
from scene_runs import run_scene as start_run

from psph.config.load import run_scene
from psph.io.snapshots import read_snapshots
from psph.verify.collapse import collapse_metrics
from psph.verify.pressure import excess_pressure, phreatic_excess, pressure_quality

ROOT = Path(__file__).resolve().parents[2]

CASES = {"-5": "collapse_saturated_psi-5", "0": "collapse_saturated_psi0",
         "2.5": "collapse_saturated_psi2.5"}


def case_row(run: Path) -> dict:
    scene = run_scene(run)
    dx = scene.particles.dx
    snaps = read_snapshots(run / "particles.h5")
    x0 = snaps[0]["x"]
    q = pressure_quality(snaps, scene)["over_run"]
    at = min(snaps, key=lambda s: abs(s["time"] - 0.6))
    end = snaps[-1]
    m_at = collapse_metrics(at["x"], x0, dx)
    m_end = collapse_metrics(end["x"], x0, dx)
    band = end["eps_p"] > 0.05

    def band_median(excess) -> float:
        return float(np.median(excess(end, scene)[band])) / 1e3 if band.any() else 0.0

    return {"band_excess_median_end_kPa": band_median(excess_pressure),
            "band_phreatic_excess_median_end_kPa": band_median(phreatic_excess),
            "abs_phreatic_excess_p99_kPa": q["abs_phreatic_excess_p99_max_Pa"] / 1e3,
            "suction_p99_kPa": q["suction_p99_max_Pa"] / 1e3,
            "runout_0.6_m": m_at["runout_m"], "t_end_s": end["time"],
            "runout_end_m": m_end["runout_m"], "excess_max_kPa": q["excess_max_Pa"] / 1e3,
            "excess_min_kPa": q["excess_min_Pa"] / 1e3,
            "abs_excess_p99_kPa": q["abs_excess_p99_max_Pa"] / 1e3,
            "checkerboard_p_eff_debris": q["checkerboard_p_eff_debris_last"],
            "back_scarp_end_m": m_end["back_scarp_m"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=Path, default=ROOT / "runs",
                    help="directory holding the runs collapse_saturated_psi* (default runs)")
    ap.add_argument("--quick", action="store_true",
                    help="run psi = 0 at dx = 0.16 m to 20 ms into <out> first, and table it")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "out",
                    help="directory of collapse_table.json (default bench/out)")
    args = ap.parse_args()
    if args.quick:
        args.runs = args.out / "collapse_table-runs"
        start_run(args.runs / CASES["0"], CASES["0"], 1,
                  ["particles.dx=0.16", "time.end=0.02", "output.interval=0.01"], False)
    rows = {}
    for psi, name in CASES.items():
        run = args.runs / name
        if (run / "particles.h5").is_file():
            rows[psi] = case_row(run)
    print(f"{'psi':>5s} {'run-out 0.6 s':>13s} {'run-out end':>11s} {'max excess kPa':>14s} "
          f"{'min excess kPa':>14s} {'p99 |excess|':>12s} {'band median':>11s} {'cb p_eff':>8s} "
          f"{'back scarp':>10s}")
    for psi, r in rows.items():
        cb = r["checkerboard_p_eff_debris"]
        print(f"{psi:>5s} {r['runout_0.6_m']:13.2f} {r['runout_end_m']:11.2f} "
              f"{r['excess_max_kPa']:14.1f} {r['excess_min_kPa']:14.1f} "
              f"{r['abs_excess_p99_kPa']:12.1f} {r['band_excess_median_end_kPa']:11.1f} "
              f"{'-' if cb is None else f'{cb:.3f}':>8s} "
              f"{r['back_scarp_end_m']:10.2f}")
    print(f"\nover the phreatic line (kPa):\n{'psi':>5s} {'p99 |excess|':>12s} "
          f"{'band median':>11s} {'p99 suction':>11s}")
    for psi, r in rows.items():
        print(f"{psi:>5s} {r['abs_phreatic_excess_p99_kPa']:12.1f} "
              f"{r['band_phreatic_excess_median_end_kPa']:11.1f} {r['suction_p99_kPa']:11.1f}")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "collapse_table.json").write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()

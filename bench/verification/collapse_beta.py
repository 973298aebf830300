"""Eq. (47) on and off in the dilative saturated collapse (collapse_saturated_psi2.5),
side by side as in the paper's Fig. 16: pore pressure frames, and against time the most
negative pore pressure (history.csv, every 1 ms) and the suction of the whole column,
the integral of max(-p, 0) over the particles' areas (kN/m, every snapshot, 0.05 s).
The paper: without Eq. (47) "the development of negative pore-water pressure is
over-predicted"; with it the change rate is kept and "the collapse of the soil column is
still processed". The frames show the excess pore pressure over the phreatic line, as
`psph plot` draws it for a drained surface (`psph.analysis.plot.excess_of`): above the line it is
p itself, the paper's "negative pore-water pressure (i.e., equal to excess pore-water
pressure in this case)".

    python bench/verification/collapse_beta.py            # runs both on 2 ranks to 1.2 s (~5-7 min)
    python bench/verification/collapse_beta.py --plot-only
    python bench/verification/collapse_beta.py --quick      # dx 0.16 m to 10 ms (a smoke check)

Prints the suction table, writes <out>/collapse_beta.json and .png (`--out`, default
bench/out; the runs go to <out>/collapse_beta_0 and _1). A run that fails (exit 3) is
drawn up to its last snapshot.
"""

import argparse
import csv
import json
import os
import subprocess
import sys
from datetime import date
from pathlib import Path

import numpy as np

from psph.analysis.plot import excess_label, excess_of
from psph.config.load import load_scene
from psph.io.snapshots import read_snapshots
from psph.verify.pressure import PHREATIC_ROWS, suction_integral, wet_threshold

ROOT = Path(__file__).resolve().parents[2]

OUT = Path(__file__).resolve().parents[1] / "out"
CASES = {"Eq. (47) on, beta = 0.04": 0.04, "Eq. (47) off, beta = 0": 0.0}
# Fig. 15's frames, after one at the peak of the suction without Eq. (47)
END, TIMES = 1.2, [0.15, 0.3, 0.6, 1.2]
EVERY = 0.05  # s between the snapshots of the suction integral
SETTINGS: list[str] = []  # further --set lines of both runs (--quick's dx)


def run_case(beta: float, out: Path) -> int:
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")
    cmd = ["mpirun", "-n", "2", sys.executable, "-m", "psph", "run",
           "collapse_saturated_psi2.5", "--out", str(out), "--quiet",
           "--set", f"pressure.beta={beta}", "--set", f"time.end={END}",
           "--set", f"output.times={TIMES}", "--set", f"output.interval={EVERY}"]
    cmd += [a for kv in SETTINGS for a in ("--set", kv)]
    return subprocess.run(cmd, env=env, cwd=ROOT).returncode


def suction_series(out: Path) -> dict:
    """At each snapshot of the run in `out`: the suction integral (kN/m,
    `suction_integral`), the particles with p below -gamma_l 2 dx and the most negative p."""
    scene = load_scene("collapse_saturated_psi2.5")
    threshold = -wet_threshold(scene)
    snaps = read_snapshots(out / "particles.h5") if (out / "particles.h5").is_file() else []
    return {"t": [float(s["time"]) for s in snaps],
            "suction_kN_per_m": [suction_integral(s) / 1e3 for s in snaps],
            "particles_in_suction": [int((s["p"] < threshold).sum()) for s in snaps],
            "p_min_kPa": [float(s["p"].min()) / 1e3 for s in snaps]}


def measure(report: dict, codes: dict[str, int]) -> None:
    """Fill `report` from the two runs' directories (history.csv, snapshots, summary)."""
    for i, (label, beta) in enumerate(CASES.items()):
        out = OUT / f"collapse_beta_{i}"
        hist = out / "history.csv"  # absent if the run failed before its first snapshot
        rows = list(csv.DictReader(hist.open())) if hist.is_file() else []
        report["cases"][label] = case = {
            "beta": beta, "exit_code": codes.get(label), "dir": str(out),
            "t": [float(r["time"]) for r in rows], "p_min": [float(r["p_min"]) for r in rows],
            "snapshots": suction_series(out)}
        summary = out / "summary.json"  # written by a run that finished
        if summary.is_file():
            case["runout_m"] = json.loads(summary.read_text())["metrics"]["collapse"]["runout_m"]
        if case["t"]:
            print(f"{label}: exit {case['exit_code']}, most negative p "
                  f"{min(case['p_min']):.4g} Pa by t = {case['t'][-1]:.3f} s, run-out "
                  f"{case.get('runout_m', '-')} m")
        else:
            print(f"{label}: exit {case['exit_code']} before its first snapshot")
    print_table(report)


def print_table(report: dict) -> None:
    """The suction of both runs side by side at their common snapshot times."""
    (a_label, a), (b_label, b) = report["cases"].items()
    sa, sb = a["snapshots"], b["snapshots"]
    print(f"suction of the column: integral of max(-p, 0) dA (kN/m), particles below "
          f"-gamma_l {PHREATIC_ROWS:g} dx, most negative p (kPa)\n"
          f"  A: {a_label}   B: {b_label}")
    print(f"{'t (s)':>6s} {'int A':>7s} {'int B':>7s} {'B/A':>6s} {'count A':>8s} "
          f"{'count B':>8s} {'min A':>7s} {'min B':>7s}")
    index_b = {round(t, 3): k for k, t in enumerate(sb["t"])}
    for k, t in enumerate(sa["t"]):
        j = index_b.get(round(t, 3))
        if j is None or t == 0.0:
            continue
        ia, ib = sa["suction_kN_per_m"][k], sb["suction_kN_per_m"][j]
        ratio = f"{ib / ia:6.2f}" if ia > 0 else f"{'-':>6s}"
        print(f"{t:6.2f} {ia:7.2f} {ib:7.2f} {ratio} {sa['particles_in_suction'][k]:8d} "
              f"{sb['particles_in_suction'][j]:8d} {sa['p_min_kPa'][k]:7.2f} "
              f"{sb['p_min_kPa'][j]:7.2f}")


def main(run: bool = True) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    report = {"date": str(date.today()), "cases": {}}
    if run:
        codes = {label: run_case(beta, OUT / f"collapse_beta_{i}")
                 for i, (label, beta) in enumerate(CASES.items())}
    else:  # the exit codes of the runs measured, as the last full run recorded them
        old = OUT / "collapse_beta.json"
        cases = json.loads(old.read_text())["cases"] if old.is_file() else {}
        codes = {label: case.get("exit_code") for label, case in cases.items()}
    measure(report, codes)
    (OUT / "collapse_beta.json").write_text(json.dumps(report, indent=1) + "\n")
    plot(report)


def plot(report: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = report["cases"]
    fig = plt.figure(figsize=(13, 9.5))
    grid = fig.add_gridspec(len(TIMES) + 1, 2, height_ratios=[1] * len(TIMES) + [1.2])
    scene = load_scene("collapse_saturated_psi2.5")
    frames = {label: read_snapshots(Path(case["dir"]) / "particles.h5")
              for label, case in cases.items()}
    # one colour scale for both columns: the largest |excess| shown, up to 10 kPa
    lim = 10.0 * np.ceil(max(np.abs(excess_of(s, scene)).max() / 1e4
                             for snaps in frames.values() for s in snaps) or 1.0)
    for c, (label, case) in enumerate(cases.items()):
        snaps = {round(s["time"], 3): s for s in frames[label]}
        for r, t in enumerate(TIMES):
            ax = fig.add_subplot(grid[r, c])
            s = min(snaps.values(), key=lambda s: abs(s["time"] - t))
            if abs(s["time"] - t) > 1e-3:
                code = case["exit_code"]
                ax.text(0.5, 0.5, f"failed before t = {t} s (exit {code})" if code
                        else f"no snapshot at t = {t} s",
                        ha="center", va="center", transform=ax.transAxes)
                ax.set_axis_off()
                continue
            ex = excess_of(s, scene) / 1e3
            sc = ax.scatter(s["x"][:, 0], s["x"][:, 1], c=np.clip(ex, -lim, lim),
                            s=1.2, cmap="RdBu_r", vmin=-lim, vmax=lim)
            ax.set_xlim(1.5, 5.5)
            ax.set_ylim(0, 2.0)
            ax.set_aspect("equal")
            ax.set_title(f"{label}: t = {s['time']:.3g} s ({ex.min():.0f} to "
                         f"{ex.max():.0f} kPa)", fontsize=9)
            fig.colorbar(sc, ax=ax, label="kPa", shrink=0.8)
    ax = fig.add_subplot(grid[-1, 0])
    for label, case in cases.items():
        ax.plot(case["t"], np.array(case["p_min"]) / 1e3, label=label)
    if min(min(c["p_min"], default=0.0) for c in cases.values()) < -1e6:
        ax.set_yscale("symlog", linthresh=100)  # a run-away reaches MPa
    ax.set_xlabel("t (s)")
    ax.set_ylabel("most negative p (kPa)")
    ax.legend(fontsize=8)
    ax = fig.add_subplot(grid[-1, 1])
    for label, case in cases.items():
        snap = case.get("snapshots", {"t": [], "suction_kN_per_m": []})
        ax.plot(snap["t"], snap["suction_kN_per_m"], "o-", ms=3, label=label)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("suction of the column,\nintegral of max(-p, 0) dA (kN/m)")
    ax.legend(fontsize=8)
    fig.suptitle(f"collapse_saturated_psi2.5 with and without Eq. (47): "
                 f"{excess_label(scene)}, {report['date']}", fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "collapse_beta.png", dpi=100)
    print(f"wrote {OUT / 'collapse_beta.png'}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plot-only", action="store_true", help="redraw from the JSON")
    ap.add_argument("--measure-only", action="store_true",
                    help="measure the runs already in <out>/collapse_beta_{0,1}")
    ap.add_argument("--quick", action="store_true",
                    help="both runs at dx = 0.16 m to 10 ms (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the runs, the JSON and the PNG (default bench/out)")
    args = ap.parse_args()
    OUT = args.out
    if args.quick:
        END, TIMES, EVERY, SETTINGS = 0.01, [0.005, 0.01], 0.005, ["particles.dx=0.16"]
    if args.plot_only:
        plot(json.loads((OUT / "collapse_beta.json").read_text()))
    else:
        main(run=not args.measure_only)

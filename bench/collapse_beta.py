"""Eq. (47) on and off in the dilative saturated collapse (collapse_saturated_psi2.5),
side by side as in the paper's Fig. 16: pore pressure frames and the most negative pore
pressure against time. The frames show the excess pore pressure (psph/verify/pressure.py).

    python bench/collapse_beta.py            # runs both on 2 ranks to 1.2 s (~8 min)
    python bench/collapse_beta.py --plot-only

Writes bench/out/collapse_beta.json and bench/out/collapse_beta.png. A run that fails
(exit 3) is drawn up to its last snapshot.
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

ROOT = Path(__file__).parent.parent
sys.path.insert(0, str(ROOT))
from psph.io.snapshots import read_snapshots  # noqa: E402
from psph.scene import load_scene  # noqa: E402
from psph.verify.pressure import excess_pressure  # noqa: E402

OUT = Path(__file__).parent / "out"
CASES = {"Eq. (47) on, beta = 0.04": 0.04, "Eq. (47) off, beta = 0": 0.0}
END, TIMES = 1.2, [0.3, 0.6, 1.2]  # Fig. 15's frames


def run_case(beta: float, out: Path) -> int:
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")
    cmd = ["mpirun", "-n", "2", sys.executable, "-m", "psph", "run",
           "collapse_saturated_psi2.5", "--out", str(out), "--quiet",
           "--set", f"pressure.beta={beta}", "--set", f"time.end={END}",
           "--set", f"output.times={TIMES}", "--set", "output.interval=0.0"]
    return subprocess.run(cmd, env=env, cwd=ROOT).returncode


def main() -> None:
    OUT.mkdir(exist_ok=True)
    report = {"date": str(date.today()), "cases": {}}
    for i, (label, beta) in enumerate(CASES.items()):
        out = OUT / f"collapse_beta_{i}"
        code = run_case(beta, out)
        hist = out / "history.csv"  # absent if the run failed before its first snapshot
        rows = list(csv.DictReader(hist.open())) if hist.is_file() else []
        report["cases"][label] = {
            "beta": beta, "exit_code": code, "dir": str(out),
            "t": [float(r["time"]) for r in rows], "p_min": [float(r["p_min"]) for r in rows]}
        case = report["cases"][label]
        summary = out / "summary.json"  # written by a run that finished
        if summary.is_file():
            case["runout_m"] = json.loads(summary.read_text())["metrics"]["collapse"]["runout_m"]
        if case["t"]:
            print(f"{label}: exit {code}, most negative p {min(case['p_min']):.4g} Pa"
                  f" by t = {case['t'][-1]:.3f} s, run-out {case.get('runout_m', '-')} m")
        else:
            print(f"{label}: exit {code} before its first snapshot")
    (OUT / "collapse_beta.json").write_text(json.dumps(report, indent=1) + "\n")
    plot(report)


def plot(report: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = report["cases"]
    fig = plt.figure(figsize=(13, 8))
    grid = fig.add_gridspec(len(TIMES) + 1, 2, height_ratios=[1] * len(TIMES) + [1.2])
    scene = load_scene("collapse_saturated_psi2.5")
    frames = {label: read_snapshots(Path(case["dir"]) / "particles.h5")
              for label, case in cases.items()}
    # one colour scale for both columns: the largest |excess| shown, up to 10 kPa
    lim = 10.0 * np.ceil(max(np.abs(excess_pressure(s, scene)).max() / 1e4
                             for snaps in frames.values() for s in snaps) or 1.0)
    for c, (label, case) in enumerate(cases.items()):
        snaps = {round(s["time"], 3): s for s in frames[label]}
        for r, t in enumerate(TIMES):
            ax = fig.add_subplot(grid[r, c])
            s = min(snaps.values(), key=lambda s: abs(s["time"] - t))
            if abs(s["time"] - t) > 1e-3:
                ax.text(0.5, 0.5, f"failed before t = {t} s (exit {case['exit_code']})",
                        ha="center", va="center", transform=ax.transAxes)
                ax.set_axis_off()
                continue
            ex = excess_pressure(s, scene) / 1e3
            sc = ax.scatter(s["x"][:, 0], s["x"][:, 1], c=np.clip(ex, -lim, lim),
                            s=1.2, cmap="RdBu_r", vmin=-lim, vmax=lim)
            ax.set_xlim(1.5, 5.5)
            ax.set_ylim(0, 2.0)
            ax.set_aspect("equal")
            ax.set_title(f"{label}: t = {s['time']:.3g} s (excess p {ex.min():.0f} to "
                         f"{ex.max():.0f} kPa)", fontsize=9)
            fig.colorbar(sc, ax=ax, label="excess p (kPa)", shrink=0.8)
    ax = fig.add_subplot(grid[-1, :])
    for label, case in cases.items():
        ax.plot(case["t"], np.array(case["p_min"]) / 1e3, label=label)
    if min(min(c["p_min"], default=0.0) for c in cases.values()) < -1e6:
        ax.set_yscale("symlog", linthresh=100)  # a run-away reaches MPa
    ax.set_xlabel("t (s)")
    ax.set_ylabel("most negative p (kPa)")
    ax.legend()
    fig.suptitle(f"collapse_saturated_psi2.5 with and without Eq. (47), {report['date']}",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "collapse_beta.png", dpi=100)
    print(f"wrote {OUT / 'collapse_beta.png'}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--plot-only", action="store_true")
    if ap.parse_args().plot_only:
        plot(json.loads((OUT / "collapse_beta.json").read_text()))
    else:
        main()

"""Eq. (47) and the time step (issue 17): the saturated collapse (collapse_saturated_psi0,
non-local law, l_c = 0.06 m, dx = 0.04 m) over its first 10 ms at dt = 2e-5 s (the
scene's) and 1e-5 s, with the scene's TPI and Eq. (47) (beta = 0.04), without Eq. (47)
(beta = 0), with TPI at alpha = 0, and with the projection (the solve of the mass
balance every step, `pressure.scheme = "projection"`). A scheme whose two steps give the
same kinetic energy and most negative p is in its asymptotic range in dt here.

    python bench/diagnostics/eq47_step.py            # 8 runs on 1 rank, about 2.5 min
    python bench/diagnostics/eq47_step.py --plot-only
    git worktree add /tmp/psph-4b3af6e 4b3af6e     # Eq. (47) as printed (before the fix)
    python bench/diagnostics/eq47_step.py --root /tmp/psph-4b3af6e --tag printed

Prints the table (kinetic energy and most negative p of `history.csv`, interpolated to
1, 2, 5 and 10 ms, and their change with the step), writes bench/out/eq47_step[-TAG].json and
bench/out/eq47_step[-TAG].png (kinetic energy and most negative p against time).
`--root DIR` runs the psph of another checkout (its `psph` package, this Python).
"""

import argparse
import json
import platform
import subprocess
import sys
from datetime import date
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(__file__).resolve().parents[1] / "out"
END = 0.0105  # history.csv has a row about every 1 ms: one past 10 ms before the end
TIMES = (0.001, 0.002, 0.005, 0.01)
STEPS = (2e-5, 1e-5)
BASE = ["material.plasticity.regularisation={kind='nonlocal', length=0.06}",
        f"time.end={END}", f"output.interval={END}"]
VARIANTS = {
    "TPI, Eq. (47) beta = 0.04": [],
    "TPI, beta = 0": ["pressure.beta=0.0"],
    "TPI alpha = 0, beta = 0.04": ["pressure.alpha=0.0"],
    "projection": ["pressure.scheme='projection'", "pressure.tolerance=1e-6"],
}


def run_case(sets: list[str], dt: float, out: Path, root: Path = ROOT) -> dict:
    """One run on 1 rank of the psph in `root`; history.csv's kinetic energy and p_min at
    TIMES."""
    cmd = [sys.executable, "-m", "psph", "run", "collapse_saturated_psi0", "--out", str(out),
           "--quiet"]
    for s in BASE + sets + [f"time.dt={dt!r}"]:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, cwd=root)
    h = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    run = {"dt": dt, "time_s": h["time"].tolist(), "kinetic_energy": h["kinetic_energy"].tolist(),
           "p_min": h["p_min"].tolist()}
    return run | {"at": at_times(run)}


def at_times(run: dict) -> dict:
    """Kinetic energy and most negative p at TIMES, interpolated linearly between the
    history.csv rows (about 1 ms apart)."""
    ke = np.interp(TIMES, run["time_s"], run["kinetic_energy"])
    p_min = np.interp(TIMES, run["time_s"], run["p_min"])
    return {f"{t:g}": {"kinetic_energy": float(k), "p_min": float(q)}
            for t, k, q in zip(TIMES, ke, p_min, strict=True)}


def table(report: dict) -> None:
    print("(history.csv's rows, about 1 ms apart, interpolated linearly to t)")
    print(f"{'variant':28s} {'t (ms)':>6s} {'KE dt':>9s} {'KE dt/2':>9s} {'change':>7s} "
          f"{'p_min dt':>9s} {'p_min dt/2':>10s} {'ratio':>6s}")
    for name, runs in report["variants"].items():
        a, b = at_times(runs[0]), at_times(runs[1])
        for t in a:
            ka, kb = a[t]["kinetic_energy"], b[t]["kinetic_energy"]
            pa, pb = a[t]["p_min"], b[t]["p_min"]
            ratio = pa / pb if pb else float("nan")
            print(f"{name:28s} {1e3 * float(t):6g} {ka:9.4g} {kb:9.4g} {(ka - kb) / kb:7.1%} "
                  f"{pa:9.4g} {pb:10.4g} {ratio:6.2f}")


def plot(report: dict, path: Path, tag: str = "") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    for i, (name, runs) in enumerate(report["variants"].items()):
        for run, style in zip(runs, ("-", "--"), strict=True):
            t = 1e3 * np.asarray(run["time_s"])
            label = f"{name}, dt = {run['dt']:g} s"
            ax.plot(t, run["kinetic_energy"], style, color=f"C{i}", label=label)
            bx.plot(t, 1e-3 * np.asarray(run["p_min"]), style, color=f"C{i}")
    ax.set_xlabel("t (ms)")
    ax.set_ylabel("kinetic energy (J/m)")
    bx.set_xlabel("t (ms)")
    bx.set_ylabel("most negative p (kPa)")
    ax.legend(fontsize=7)
    fig.suptitle("collapse_saturated_psi0, first 10 ms: solid dt = 2e-5 s, dashed 1e-5 s"
                 + (f" [{tag}]" if tag else ""))
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--root", type=Path, default=ROOT, help="the checkout whose psph runs")
    ap.add_argument("--tag", default="", help="a suffix for the output names and title")
    args = ap.parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    name = "eq47_step" + (f"-{args.tag}" if args.tag else "")
    path = OUT / f"{name}.json"
    if args.plot_only:
        report = json.loads(path.read_text())
    else:
        root = args.root.resolve()
        report = {"date": str(date.today()), "machine": platform.node(), "root": str(root),
                  "variants": {}}
        for i, (variant, sets) in enumerate(VARIANTS.items()):
            report["variants"][variant] = [
                run_case(sets, dt, OUT / name / f"{i}_{dt:g}", root) for dt in STEPS]
        path.write_text(json.dumps(report, indent=1))
    table(report)
    plot(report, OUT / f"{name}.png", args.tag)
    return 0


if __name__ == "__main__":
    sys.exit(main())

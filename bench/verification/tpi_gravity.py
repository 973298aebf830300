"""Stability of TPI (Eq. 38-39) under gravity: the `geostatic_column` at rest, run with
`pressure.scheme = "tpi"`, over alpha and the gain G = dt gamma_l / (rho k).

Eq. (38) has no storage term: p answers div v at once with gain gamma_l / sum_j A_ij
(proportional to h^2 / k), and grad p feeds back into v. This acts like an explicit bulk
viscosity gamma_l / (rho sum A), and the bound comes out independent of h: dt < C(alpha)
rho k / gamma_l (measured, not derived; every dt here is below the solid limit Eq. (41)
of the column, 6.9e-5 s). A run is stable if it reaches `--end` (default 0.3 s) without a
numerical failure.

    python bench/verification/tpi_gravity.py            # table, <out>/tpi_gravity.json and .png
    python bench/verification/tpi_gravity.py --plot-only
    python bench/verification/tpi_gravity.py --no-gravity   # the loaded Terzaghi column instead
    python bench/verification/tpi_gravity.py --quick        # one cell of the map, to 5 ms

`--projection`: the same geostatic column with `pressure.scheme = "projection"` (the
symplectic step) at every dt of the map (k = 2e-4, G = 0.2 ... 1.2) and at the solid
cap Eq. (41), 100,000 steps each at rest; a run passes if it ends without a numerical
failure and its particles are at rest (max |v| over the last snapshot below
`V_REST`); writes projection_gravity.json.

`--no-gravity`: the `terzaghi` column (dx = 0.01, no gravity) loaded with 50 kPa through its
explicit stage, then TPI from the drained switch (0.01 s) to 0.05 s, symplectic step; G set
through k at dt = 9.786e-6 s (below the solid cap); writes tpi_nogravity.json / .png.
"""

import argparse
import json
import math
import subprocess
import sys
from datetime import date
from pathlib import Path

import numpy as np

from psph.physics.limits import tpi_gain_limit

OUT = Path(__file__).resolve().parents[1] / "out"
ROOT = Path(__file__).resolve().parents[2]
ALPHAS = (0.0, 0.3, 0.5, 0.7)
GAINS = (0.2, 0.3, 0.35, 0.4, 0.5, 0.55, 0.6, 0.8, 0.9, 1.0, 1.1, 1.2)
GAMMA, RHO = 9810.0, 0.65 * 2650.0 + 0.35 * 1000.0


V_REST = 1e-4  # m/s: "at rest" for the projection rows (the K0 state's first settling
# moves the column by a few micrometres)
SOLID_CAP = 6.9e-5  # s, Eq. (41) for the geostatic column (dx = 0.05)
NG_DT, NG_RHO = 9.786e-6, 0.6 * 2000.0 + 0.4 * 1000.0  # the terzaghi column's soil
NG_GAINS = (0.2, 0.3, 0.45, 0.6, 0.9, 1.2, 1.6, 2.4, 3.6)


def run(alpha: float, k: float, dt: float, end: float, gravity: bool = True) -> tuple[bool, int]:
    if gravity:
        scene = ["geostatic_column", "--set", "pressure.scheme='tpi'",
                 "--set", "checkpoint.at_end=false", "--set", f"output.interval={end}"]
    else:
        scene = ["terzaghi_tpi", "--set", "loads.0.pressure=5e4", "--set", "verification.tv=[]",
                 "--set", "time.integrator='symplectic'", "--set", "output.interval=0.0"]
    r = subprocess.run(
        [sys.executable, "-m", "psph", "run", *scene, "--quiet",
         "--out", str(OUT / "tpi_gravity_run"),
         "--set", f"pressure.alpha={alpha}", "--set", f"material.k={k}",
         "--set", "pressure.allow_unstable=true",
         "--set", f"time.dt={dt!r}", "--set", f"time.end={end}"],
        capture_output=True, text=True, cwd=ROOT)
    if r.returncode not in (0, 3):
        raise RuntimeError(r.stderr)
    step = 0
    if r.returncode == 3:
        step = int(r.stderr.split("step ")[1].split(",")[0])
    return r.returncode == 0, step


def main(end: float, k: float) -> None:
    rows = []
    for alpha in ALPHAS:
        for g in GAINS:
            dt = g * RHO * k / GAMMA
            ok, step = run(alpha, k, dt, end)
            rows.append({"alpha": alpha, "gain": g, "dt": dt, "k": k, "stable": ok,
                         "failed_at_step": step})
            print(f"alpha {alpha:.1f}  G {g:.2f}  dt {dt:.2e}  "
                  f"{'stable' if ok else f'failed at step {step}'}", flush=True)
    report = {"date": str(date.today()), "end_s": end, "rows": rows}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "tpi_gravity.json").write_text(json.dumps(report, indent=2) + "\n")
    table(report)
    plot(report)


def main_no_gravity(end: float) -> None:
    rows = []
    for alpha in ALPHAS:
        for g in NG_GAINS:
            k = NG_DT * GAMMA / (g * NG_RHO)
            ok, step = run(alpha, k, NG_DT, end, gravity=False)
            rows.append({"alpha": alpha, "gain": g, "dt": NG_DT, "k": k, "stable": ok,
                         "failed_at_step": step})
            print(f"alpha {alpha:.1f}  G {g:.2f}  k {k:.3g}  "
                  f"{'stable' if ok else f'failed at step {step}'}", flush=True)
    report = {"date": str(date.today()), "end_s": end, "rows": rows, "gravity": False}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "tpi_nogravity.json").write_text(json.dumps(report, indent=2) + "\n")
    table(report)
    plot(report)


def main_projection(steps: int) -> None:
    """The projection over the map's dt and the solid cap, `steps` steps at rest each."""
    from psph.io.snapshots import read_snapshots

    out = OUT / "projection_gravity_run"
    rows = []
    for g in GAINS + (SOLID_CAP * GAMMA / (RHO * 2e-4),):
        dt = g * RHO * 2e-4 / GAMMA
        end = steps * dt
        r = subprocess.run(
            [sys.executable, "-m", "psph", "run", "geostatic_column", "--quiet",
             "--out", str(out), "--set", "pressure.scheme='projection'",
             "--set", "time.integrator='symplectic'", "--set", "checkpoint.at_end=false",
             "--set", f"output.interval={end}", "--set", f"time.dt={dt!r}",
             "--set", f"time.end={end!r}", "--set", "pressure.tolerance=1e-9"],
            capture_output=True, text=True, cwd=ROOT)
        if r.returncode not in (0, 3):
            raise RuntimeError(r.stderr)
        vmax = math.inf
        if r.returncode == 0:
            last = read_snapshots(out / "particles.h5")[-1]
            vmax = float(np.max(np.linalg.norm(last["v"], axis=1)))
        summary = json.loads((out / "summary.json").read_text()) if r.returncode == 0 else {}
        ok = r.returncode == 0 and vmax < V_REST
        rows.append({"gain": g, "dt": dt, "k": 2e-4, "steps": summary.get("steps"),
                     "stable": ok, "v_max_end": vmax,
                     "cg_iterations_mean": summary.get("pressure_solve", {}).get(
                         "iterations_mean")})
        print(f"G {g:.2f}  dt {dt:.3e}  {summary.get('steps')} steps  "
              f"max |v| {vmax:.2e} m/s  {'at rest' if ok else 'FAILED'}", flush=True)
    report = {"date": str(date.today()), "steps": steps, "v_rest": V_REST, "rows": rows}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "projection_gravity.json").write_text(json.dumps(report, indent=2) + "\n")
    print(f"projection, geostatic column, {steps} steps: "
          f"{sum(r['stable'] for r in rows)} of {len(rows)} at rest "
          f"(max |v| < {V_REST} m/s); wrote {OUT / 'projection_gravity.json'}")


def table(report: dict) -> None:
    gravity = report.get("gravity", True)
    gains = GAINS if gravity else NG_GAINS
    name = "tpi_gravity" if gravity else "tpi_nogravity"
    what = "TPI under gravity, geostatic_column" if gravity else \
        "TPI without gravity, loaded terzaghi column"
    print(f"\n{what} to {report['end_s']} s, {report['date']}")
    print("alpha | " + " ".join(f"{g:<5}" for g in gains) + "   (G)")
    for a in ALPHAS:
        cells = [r for r in report["rows"] if r["alpha"] == a]
        print(f"{a:5.1f} | " + " ".join(f"{'ok' if r['stable'] else 'x':5s}" for r in cells))
    print(f"wrote {OUT / (name + '.json')}")


def plot(report: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.5, 3.6))
    for r in report["rows"]:
        ax.plot(r["gain"], r["alpha"], "o" if r["stable"] else "x",
                color="C2" if r["stable"] else "C3", ms=8)
    ax.plot([], [], "o", color="C2", label="stable")
    ax.plot([], [], "x", color="C3", label="blows up")
    gravity = report.get("gravity", True)
    if gravity:
        ax.axvline(0.47, ls=":", c="grey", label="paper's collapse (G = 0.47)")
    a = [0.01 * i for i in range(76)]
    bound = [tpi_gain_limit(x, gravity) for x in a]
    label = r"bound 1.15 (1 - $\alpha$)" if gravity else r"bound min(5 (1 - $\alpha)^2$, 3.6)"
    ax.plot(bound, a, "k--", lw=1, label=label + " (validation)")
    ax.set_xlabel(r"G = $\Delta t\,\gamma_l / (\rho k)$")
    ax.set_ylabel(r"TPI $\alpha$")
    ax.set_title("TPI with gravity: geostatic column" if gravity else
                 "TPI without gravity: loaded Terzaghi column", fontsize=10)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    name = "tpi_gravity" if gravity else "tpi_nogravity"
    fig.savefig(OUT / f"{name}.png", dpi=110)
    print(f"wrote {OUT / (name + '.png')}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--end", type=float, default=0.3)
    ap.add_argument("--k", type=float, default=2e-4)
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--no-gravity", action="store_true")
    ap.add_argument("--projection", action="store_true")
    ap.add_argument("--steps", type=int, default=100_000)
    ap.add_argument("--quick", action="store_true",
                    help="one cell of the map, alpha = 0.5 and G = 0.3, to 5 ms (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the runs, the JSON and the PNG (default bench/out)")
    a = ap.parse_args()
    OUT = a.out
    if a.quick:
        ALPHAS, GAINS, a.end = (0.5,), (0.3,), 0.005
    if a.projection:
        main_projection(a.steps)
    elif a.plot_only:
        rep = json.loads((OUT / ("tpi_nogravity.json" if a.no_gravity
                                 else "tpi_gravity.json")).read_text())
        table(rep)
        plot(rep)
    elif a.no_gravity:
        main_no_gravity(0.05 if a.end == 0.3 else a.end)
    else:
        main(a.end, a.k)

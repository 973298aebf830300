"""Stability map of the TPI update Eq. (38)-(39) over R and alpha, and a long run.

Map: the CI-sized Terzaghi column (dx = 0.02 m, 250 particles) at a fixed dt = 1e-5 s
(below the solid cap Eq. 41); R = dt / dt_Eq42 is swept through the permeability k, since
Eq. (42) is inversely proportional to k (the paper: "R is proportional to permeability").
Loading: 10 kPa over 1 ms, explicit, all sides impervious; then the top drains and TPI
runs N_TPI steps. A run is unstable on a NumericalError (NaN/inf, a particle leaving the
domain), on p_max > 2 q, or on growth of the pressure oscillation (the step-to-step
second difference of p at the column base, last quarter vs first quarter, > 3x and > 1 % q).

Long run: the same column with the `terzaghi` settings (alpha = 0.5, dt = 5e-6 s) for
10x the usual duration (T_v = 10); kinetic energy and p_max must stay bounded.

    python bench/verification/stability.py          # ~10 min on this machine
    python bench/verification/stability.py --plot-only
    python bench/verification/stability.py --projection   # the R row with the projection
    python bench/verification/stability.py --quick        # R = 100, alpha = 0.7, 500 steps

Writes <out>/stability.json and .png.
"""

import argparse
import json
import platform
import tempfile
from datetime import date
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[1] / "out"
Q = 1.0e4
DT = 1.0e-5
N_TPI = 20000
R_VALUES = (10, 35, 70, 100, 150, 200, 250, 300, 400)
ALPHAS = (0.0, 0.25, 0.5, 0.7, 0.75, 0.8, 0.9)
COLUMN = ["particles.dx=0.02", "verification.tv=[]", "output.interval=0.0", "output.times=[]",
          "loads.0.ramp=0.001", "pressure.explicit_until=0.001",
          "boundaries.top.drained_from=0.001", "output.probes={ base = [0.05, 0.01] }",
          "pressure.allow_unstable=true"]  # the map crosses the bound validation enforces


def _run(overrides: list[str]) -> tuple[dict | None, dict, str | None]:
    from mpi4py import MPI

    from psph.app.run import run
    from psph.config.load import load_scene
    from psph.errors import NumericalError

    scene = load_scene("terzaghi_tpi", overrides)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            summary = run(scene, Path(tmp), comm=MPI.COMM_SELF, quiet=True)
        except NumericalError as e:
            return None, {}, str(e)
        lines = (Path(tmp) / "history.csv").read_text().split()
    keys = lines[0].split(",")
    rows = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    return summary, {k: rows[:, i] for i, k in enumerate(keys)}, None


# the pressure projection instead of TPI: one solve per step, the loading too
PROJECTION = ["pressure.scheme='projection'", "time.integrator='symplectic'",
              "pressure.explicit_until=0.0"]


def map_case(R: float, alpha: float, scheme: list[str] | None = None) -> dict:
    from psph.config.load import load_scene
    from psph.physics.limits import fluid_dt_limit

    # k such that dt_Eq42(k) = DT / R; Eq. (42) is proportional to 1/k
    ref = load_scene("terzaghi_tpi", COLUMN + ["material.k=1e-3", "time.end=1.0"])
    k = 1e-3 * fluid_dt_limit(ref) * R / DT
    end = 0.001 + N_TPI * DT
    ov = COLUMN + [f"material.k={k!r}", f"time.dt={DT}", f"pressure.alpha={alpha}",
                   f"time.end={end!r}", f"output.history_interval={20 * DT!r}"]
    summary, hist, failure = _run(ov + (scheme or []))
    rec = {"R": R, "alpha": alpha, "k": k, "scheme": "projection" if scheme else "tpi"}
    if failure:
        return rec | {"stable": False, "reason": "numerical failure", "detail": failure}
    p = hist["p_base"][hist["time"] > 0.0015]
    d2 = np.abs(np.diff(p, 2))
    quarter = max(len(d2) // 4, 1)
    early, late = d2[:quarter].max(), d2[-quarter:].max()
    growth = late / max(early, 1e-9)
    rec |= {"p_max": float(hist["p_max"].max()), "oscillation_growth": float(growth)}
    if hist["p_max"].max() > 2 * Q:
        return rec | {"stable": False, "reason": "p_max > 2 q"}
    if growth > 3 and late > 0.01 * Q:
        return rec | {"stable": False, "reason": "growing pressure oscillation"}
    return rec | {"stable": True}


def long_run() -> dict:
    from psph.config.load import load_scene
    from psph.verify.terzaghi import from_scene

    base = ["particles.dx=0.02", "material.k=8e-4", "verification.tv=[]",
            "output.interval=0.0", "output.times=[]", "output.history_interval=0.002",
            "pressure.alpha=0.5", "time.dt=5e-6"]  # the settings it was measured with
    ref = from_scene(load_scene("terzaghi_tpi", base + ["time.end=1.0"]))
    end = ref.time_of(10.0)
    summary, hist, failure = _run(base + [f"time.end={end!r}"])
    if failure:
        return {"stable": False, "detail": failure}
    t = hist["time"]
    after = t > ref.time_of(1.0)
    return {"stable": True, "end_s": end, "tv_end": 10.0, "steps": summary["steps"],
            "wall_s": summary["wall_time_s"], "time": t.tolist(),
            "kinetic_energy": hist["kinetic_energy"].tolist(), "p_max": hist["p_max"].tolist(),
            "p_max_after_tv1": float(hist["p_max"][after].max()),
            "kinetic_energy_max_after_tv1": float(hist["kinetic_energy"][after].max()),
            "kinetic_energy_max": float(hist["kinetic_energy"].max()), "p0": ref.p0}


def plot(data: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    for r in data["map"]:
        ax1.plot(r["R"], r["alpha"], "o" if r["stable"] else "x", ms=9,
                 color="tab:green" if r["stable"] else "tab:red")
    ax1.plot([], [], "o", color="tab:green", label="stable")
    ax1.plot([], [], "x", color="tab:red", label="unstable")
    ax1.plot([250], [0.0], "s", mfc="none", mec="k", ms=14, label="paper: alpha = 0 unstable > 250")
    ax1.plot([98], [0.75], "D", mfc="none", mec="k", ms=14, label="paper: R = 98, alpha > 0.75")
    ax1.set_xscale("log")
    ax1.set_xlabel("R = dt / dt_Eq42")
    ax1.set_ylabel("alpha")
    ax1.set_title(f"TPI stability, {N_TPI} steps at dt = {DT:g} s")
    ax1.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    lr = data["long"]
    if lr.get("stable"):
        t = np.array(lr["time"])
        ax2.plot(t, np.array(lr["p_max"]) / Q, label="p_max / q")
        ax2.set_xlabel("time (s)")
        ax2.set_ylabel("p_max / q")
        ax3 = ax2.twinx()
        ax3.semilogy(t, np.maximum(lr["kinetic_energy"], 1e-16), color="tab:orange",
                     label="kinetic energy (J/m)")
        ax3.set_ylabel("kinetic energy (J/m)")
        ax2.set_title(f"long column, T_v = 0 ... {lr['tv_end']:g} ({lr['steps']} steps)")
        ax2.legend(loc="upper right", fontsize=8)
        ax3.legend(loc="center right", fontsize=8)
    fig.suptitle(f"psph stability, {data['date']}, {data['machine']}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def projection_map() -> None:
    """The map's R row with the projection: the same column, dt, loading and checks."""
    rows = []
    print(f"{'R':>5}  verdict (projection)")
    for R in R_VALUES:
        r = map_case(R, 0.0, PROJECTION)
        rows.append(r)
        verdict = "stable" if r["stable"] else f"UNSTABLE ({r['reason']})"
        print(f"{R:5.0f}  {verdict}  p_max/q {r.get('p_max', float('nan')) / Q:.3f}",
              flush=True)
    path = OUT / "stability-projection.json"
    path.write_text(json.dumps({"date": date.today().isoformat(),
                                "machine": platform.node(), "map": rows}, indent=2) + "\n")
    print(f"wrote {path}")


def main() -> None:
    global OUT, N_TPI, R_VALUES, ALPHAS
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--projection", action="store_true",
                    help="the map's R row with the pressure projection (no alpha, no long "
                         "run); writes stability-projection.json")
    ap.add_argument("--quick", action="store_true",
                    help="one map case, R = 100 and alpha = 0.7, 500 TPI steps, no long run "
                         "(a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON and PNG (default bench/out)")
    args = ap.parse_args()
    OUT = args.out
    if args.quick:
        N_TPI, R_VALUES, ALPHAS = 500, (100,), (0.7,)
    OUT.mkdir(parents=True, exist_ok=True)
    if args.projection:
        projection_map()
        return
    jpath, ppath = OUT / "stability.json", OUT / "stability.png"
    if args.plot_only:
        plot(json.loads(jpath.read_text()), ppath)
        return
    rows = []
    print(f"{'R':>5} {'alpha':>5}  verdict")
    for R in R_VALUES:
        for alpha in ALPHAS:
            r = map_case(R, alpha)
            rows.append(r)
            verdict = "stable" if r["stable"] else f"UNSTABLE ({r['reason']})"
            print(f"{R:5.0f} {alpha:5.2f}  {verdict}", flush=True)
    lr = {"stable": False, "detail": "not run (--quick)"} if args.quick else long_run()
    if lr["stable"]:
        print(f"long column to T_v = 10: {lr['steps']} steps, p_max after T_v = 1: "
              f"{lr['p_max_after_tv1']:.1f} Pa (p0 = {lr['p0']:.0f}), KE max after T_v = 1: "
              f"{lr['kinetic_energy_max_after_tv1']:.3e} (overall {lr['kinetic_energy_max']:.3e})")
    else:
        print(f"long column: UNSTABLE: {lr['detail']}")
    data = {"date": date.today().isoformat(), "machine": platform.node(), "map": rows,
            "long": lr}
    jpath.write_text(json.dumps(data, indent=2) + "\n")
    plot(data, ppath)
    print(f"wrote {jpath} and {ppath}")


if __name__ == "__main__":
    main()

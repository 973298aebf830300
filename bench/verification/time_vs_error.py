"""Run time against error on Terzaghi (Section 4.1): explicit Eq. (25), TPI Eq. (38) and
the pressure projection (one CG solve of Eq. 29 per step).

Every case is the `terzaghi` scene on one rank, run to T_v = 0.5. Time is the run's
CPU time (`time.process_time`, one rank, one thread): equal to its wall time on an idle
core, and unaffected by other jobs sharing the machine; the wall time is recorded too.
The explicit scheme runs at its stable dt (Eq. 42); TPI sweeps dt (R = dt / dt_Eq42) and
alpha, with its impervious loading stage explicit (as in the paper); the projection
sweeps dt from R = 8.8 to four times the solid cap Eq. (41) at CG tolerances 1e-6 and
1e-9, and solves the loading stage too. Per case: the time of the run and the error
against the analytical solution: max |p - p_a| / q over T_v = 0.1, 0.2, 0.5, and the max
settlement error / final settlement over T_v in [0.1, 0.5].

    python bench/verification/time_vs_error.py            # the paper's column (~100 CPU min)
    python bench/verification/time_vs_error.py --jobs 2   # the same on two cores (~55 min)
    python bench/verification/time_vs_error.py --quick    # dx = 0.02, k = 8e-4 column (~3 min)
    python bench/verification/time_vs_error.py --geotaichi  # GeoTaichi's start (~5 min)
    python bench/verification/time_vs_error.py --smoke    # the --quick column to T_v = 0.005,
                                                          # one TPI case
    python bench/verification/time_vs_error.py --jobs 2 \
        --only 'explicit|alpha=0.7|projection dt=1.2'
        # a subset in one run (labels matching the regular expression; writes *-only.*)

`--geotaichi`: the `terzaghi_undrained` scene (H = 1 m, q = 10 kPa, k = 2e-4, dx = 0.02 m,
2 particles wide: 100 particles; from the undrained state with the top drained from t = 0,
as GeoTaichi's two-phase MPM starts it) against GeoTaichi's best run measured on this
machine (its run n50_f1.5_cold: 400 particles, 0.97 % of q over T_v = 0.1, 0.2, 0.5 in
37.6 CPU s of its time loop, one thread, float64).

Prints a table, writes <out>/time_vs_error[-quick|-geotaichi|-smoke][-only].json and
draws the .png beside it (error against wall time, the Pareto picture).
"""

import argparse
import json
import platform
import tempfile
import time
from datetime import date
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "out"
BASE = ["verification.tv=[0.1, 0.2, 0.5]", "output.interval=0.0", "output.times=[]"]
QUICK = ["particles.dx=0.02", "material.k=8e-4"]
BAR = 0.03  # error bar of the headline: TPI speed-up at <= 3 % error
FINE = 0.01  # the second headline: the fastest setting at <= 1 %
GEOTAICHI = {"particles": 400, "p_error": 0.0097, "cpu_s": 37.6,
             "source": "GeoTaichi's run n50_f1.5_cold, measured on this machine"}


def cases(base: list[str]) -> list[tuple[str, list[str]]]:
    """(label, --set overrides): explicit at the Eq. (42) limit, TPI over dt and alpha,
    the projection over dt (to the solid cap) and the CG tolerance."""
    from psph.config.load import load_scene
    from psph.physics.limits import fluid_dt_limit, solid_dt_limit

    scene = load_scene("terzaghi_tpi", base)
    dt_l = fluid_dt_limit(scene)
    out = [("explicit", ["pressure.scheme='explicit'", f"time.dt={dt_l!r}"])]
    for dt in (2.5e-6, 5e-6, 1e-5):
        for alpha in (0.0, 0.5, 0.7):
            out.append((f"tpi dt={dt:g} alpha={alpha:g}",
                        [f"time.dt={dt}", f"pressure.alpha={alpha}"]))
    cap = solid_dt_limit(scene)
    for dt in (2.5e-6, 5e-6, 1e-5, cap, 2 * cap, 4 * cap):
        for tol in (1e-6, 1e-9):
            out.append((f"projection dt={dt:.3g} tol={tol:g}",
                        ["pressure.scheme='projection'", "time.integrator='symplectic'",
                         "pressure.explicit_until=0.0", f"time.dt={dt!r}",
                         f"pressure.tolerance={tol}",
                         f"time.allow_dt_above_solid_limit={dt > cap}".lower()]))
    return out


def geotaichi_cases() -> list[tuple[str, list[str]]]:
    """The `terzaghi_undrained` column: explicit at Eq. (42), TPI at R = 5 and 10 (R = 21,
    the solid cap, fails: exit 3), the projection at the solid cap and at twice it."""
    from psph.config.load import load_scene
    from psph.physics.limits import fluid_dt_limit, solid_dt_limit

    scene = load_scene("terzaghi_undrained", BASE)
    dt_l, cap = fluid_dt_limit(scene), solid_dt_limit(scene)
    tpi = ["pressure.scheme='tpi'", "pressure.alpha=0.5", "time.integrator='euler'"]
    out = [("explicit", ["pressure.scheme='explicit'", "time.integrator='euler'",
                         f"time.dt={dt_l!r}"])]
    out += [(f"tpi dt={r * dt_l:.3g} alpha=0.5", tpi + [f"time.dt={r * dt_l!r}"])
            for r in (5, 10)]
    for dt in (cap, 2 * cap):
        for tol in (1e-6, 1e-9):
            out.append((f"projection dt={dt:.3g} tol={tol:g}",
                        [f"time.dt={dt!r}", f"pressure.tolerance={tol}",
                         f"time.allow_dt_above_solid_limit={dt > cap}".lower()]))
    return out


def _warm_up(scene) -> None:
    """Two steps of the same scene, untimed: numba's cached kernels load here, not in the
    timed run (a worker process starts cold; the serial loop did only for its first
    case)."""
    from mpi4py import MPI

    from psph.app.run import run
    from psph.errors import NumericalError

    short = scene.model_copy(deep=True)
    short.time.end = 2.0 * time_stepping_dt(scene)
    short.output.times = []
    short.output.interval = 0.0
    short.checkpoint.at_end = False
    with tempfile.TemporaryDirectory() as tmp:
        try:
            run(short, Path(tmp), comm=MPI.COMM_SELF, quiet=True)
        except NumericalError:
            pass  # the timed run reports it


def time_stepping_dt(scene) -> float:
    from psph.solver.stepping import time_stepping

    return time_stepping(scene).dt_explicit


def run_case(overrides: list[str], name: str = "terzaghi_tpi") -> dict:
    from mpi4py import MPI

    from psph.app.run import run
    from psph.config.load import load_scene
    from psph.errors import NumericalError
    from psph.solver.stepping import time_stepping

    scene = load_scene(name, overrides)
    st = time_stepping(scene)
    _warm_up(scene)
    rec = {"dt": st.dt_main, "R": st.dt_main / st.limits["dt_fluid_eq42"],
           "scheme": scene.pressure.scheme, "alpha": scene.pressure.alpha,
           "tolerance": scene.pressure.tolerance}
    with tempfile.TemporaryDirectory() as tmp:
        cpu0 = time.process_time()
        try:
            s = run(scene, Path(tmp), comm=MPI.COMM_SELF, quiet=True)
        except NumericalError as e:
            return rec | {"stable": False, "failure": str(e)}
        cpu = time.process_time() - cpu0
    err = s["errors"]
    return rec | {"stable": True, "wall_s": s["wall_time_s"], "cpu_s": cpu,
                  "steps": s["steps"],
                  "p_error": err["max_abs_p_error_over_q"],
                  "p_error_by_tv": {k: v["max_abs_p_error_over_q"]
                                    for k, v in err["pressure"].items()},
                  "settlement_error": err["settlement_max_abs_error_over_final"],
                  "cg_iterations_mean": s.get("pressure_solve", {}).get("iterations_mean"),
                  "particles": s.get("particles")}


def headline(rows: list[dict]) -> dict:
    """Speed-ups over explicit at its Eq. (42) limit: the fastest TPI and projection
    settings at <= 3 % (pressure and settlement), and the fastest setting at <= 1 %."""
    exp = next((r for r in rows if r["scheme"] == "explicit"), None)
    if exp is None or not exp["stable"]:  # (--only without the explicit case: no speed-up)
        return {}
    out = {"explicit_cpu_s": exp["cpu_s"], "explicit_p_error": exp["p_error"]}

    def fastest(scheme, bar):
        ok = [r for r in rows if r["stable"] and r["p_error"] <= bar
              and r["settlement_error"] <= bar and scheme in (None, r["scheme"])]
        return min(ok, key=lambda r: r["cpu_s"]) if ok else None

    for key, scheme, bar in (("tpi", "tpi", BAR), ("projection", "projection", BAR),
                             ("at_1pct", None, FINE)):
        best = fastest(scheme, bar)
        if best is not None:
            out |= {f"best_{key}": best["label"], f"best_{key}_cpu_s": best["cpu_s"],
                    f"best_{key}_p_error": best["p_error"],
                    f"speedup_{key}": exp["cpu_s"] / best["cpu_s"]}
    return out


def plot(data: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    marks = {0.0: "v", 0.5: "o", 0.7: "s"}
    for r in data["cases"]:
        if not r["stable"]:
            continue
        if r["scheme"] == "explicit":
            ax.plot(r["cpu_s"], 100 * r["p_error"], "k*", ms=14, label="explicit Eq. (25)")
            continue
        if r["scheme"] == "projection":
            ax.plot(r["cpu_s"], 100 * r["p_error"], "D" if r["tolerance"] < 1e-7 else "d",
                    ms=8, mfc="none", color=plt.cm.plasma(min(r["R"] / 100, 0.9)),
                    label=f"projection R={r['R']:.0f} tol={r['tolerance']:g}")
            continue
        ax.plot(r["cpu_s"], 100 * r["p_error"], marks[r["alpha"]], ms=8,
                color=plt.cm.viridis(min(r["R"] / 40, 1)),
                label=f"TPI R={r['R']:.0f} alpha={r['alpha']:g}")
    ax.axhline(100 * BAR, color="grey", ls="--", lw=1)
    ax.axhline(100 * FINE, color="grey", ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("run time (s, one core)")
    ax.set_ylabel("max |p - p_a| / q over T_v = 0.1, 0.2, 0.5 (%)")
    h = data.get("headline", {})
    title = f"Terzaghi, {data['column']}\n{data['date']}"
    if "speedup_at_1pct" in h:
        title += f": at <= 1 % {h['speedup_at_1pct']:.1f}x faster than explicit"
    if "geotaichi" in data:
        g = data["geotaichi"]
        ax.plot(g["cpu_s"], 100 * g["p_error"], "kX", ms=12,
                label=f"GeoTaichi MPM, {g['particles']} particles")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _labelled_case(job: tuple[str, list[str], str]) -> dict:
    label, overrides, name = job
    return {"label": label} | run_case(overrides, name)


def _results(todo, base, name, jobs):
    """The cases' results in their listed order, run `jobs` at a time (the explicit case,
    by far the longest, is first, so it starts at once)."""
    work = [(label, base + ov, name) for label, ov in todo]
    if jobs <= 1:
        yield from map(_labelled_case, work)
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    # spawn: no MPI state forked; a worker that dies raises BrokenProcessPool, no hang
    with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
        yield from pool.map(_labelled_case, work)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="coarse CI-sized column")
    ap.add_argument("--geotaichi", action="store_true",
                    help="the terzaghi_undrained column against GeoTaichi's measurement")
    ap.add_argument("--plot-only", action="store_true", help="redraw the PNG from the JSON")
    ap.add_argument("--jobs", type=int, default=1,
                    help="cases run in this many worker processes at once (one core each; "
                         "each case's CPU time is its own process's)")
    ap.add_argument("--only", metavar="REGEX",
                    help="run only the cases whose label matches (re.search), e.g. "
                         "'explicit|projection dt=1.2'; the table says which were run")
    ap.add_argument("--smoke", action="store_true",
                    help="the --quick column to T_v = 0.005, TPI at dt = 1e-5 and alpha = 0.7 "
                         "alone (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON and PNG (default bench/out)")
    args = ap.parse_args()
    tag = ("-quick" if args.quick else "-geotaichi" if args.geotaichi else
           "-smoke" if args.smoke else "") + ("-only" if args.only else "")
    if args.smoke:
        args.quick, args.geotaichi = True, False
        args.only = args.only or "^tpi dt=1e-05 alpha=0.7$"
        BASE[0] = "verification.tv=[0.005]"
    args.out.mkdir(parents=True, exist_ok=True)
    jpath, ppath = args.out / f"time_vs_error{tag}.json", args.out / f"time_vs_error{tag}.png"
    if args.plot_only:
        plot(json.loads(jpath.read_text()), ppath)
        return
    rows = []
    print(f"{'case':<30} {'R':>6} {'steps':>9} {'cpu s':>8} {'p err/q':>8} {'settl.':>8} "
          f"{'CG it':>6}")
    if args.geotaichi:
        name, base, todo = "terzaghi_undrained", BASE, geotaichi_cases()
        column = "terzaghi_undrained: dx=0.02, 2 particles wide (100), k=2e-4, undrained start"
    else:
        name, base = "terzaghi_tpi", BASE + (QUICK if args.quick else [])
        todo = cases(base)
        column = "dx=0.02, k=8e-4" if args.quick else "dx=0.01, k=2e-4 (paper), 1000 particles"
    if args.only:
        import re

        todo = [(label, ov) for label, ov in todo if re.search(args.only, label)]
        if not todo:
            raise SystemExit(f"--only {args.only!r}: no case label matches")
    for r in _results(todo, base, name, args.jobs):
        label = r["label"]
        rows.append(r)
        if r["stable"]:
            it = r["cg_iterations_mean"]
            print(f"{label:<30} {r['R']:6.1f} {r['steps']:9d} {r['cpu_s']:8.1f} "
                  f"{r['p_error']:8.4f} {r['settlement_error']:8.4f} "
                  f"{'' if it is None else f'{it:6.1f}'}", flush=True)
        else:
            print(f"{label:<30} {r['R']:6.1f}  unstable: {r['failure']}", flush=True)
    data = {"date": date.today().isoformat(), "machine": platform.node(), "jobs": args.jobs,
            "only": args.only,
            "cpu": platform.processor() or platform.machine(), "column": column,
            "cases": rows, "headline": headline(rows)}
    if args.geotaichi:
        data["geotaichi"] = GEOTAICHI
    jpath.write_text(json.dumps(data, indent=2) + "\n")
    plot(data, ppath)
    h = data["headline"]
    for key, what in (("tpi", "TPI at <= 3 %"), ("projection", "projection at <= 3 %"),
                      ("at_1pct", "the fastest setting at <= 1 %")):
        if f"best_{key}" in h:
            print(f"{what} ({h[f'best_{key}']}, {h[f'best_{key}_p_error']:.4f} of q, "
                  f"{h[f'best_{key}_cpu_s']:.1f} CPU s) is {h[f'speedup_{key}']:.1f}x faster "
                  f"than explicit at Eq. (42) ({h['explicit_p_error']:.4f}, "
                  f"{h['explicit_cpu_s']:.1f} CPU s)")
    if args.geotaichi and "best_at_1pct" in h:
        g = GEOTAICHI
        print(f"GeoTaichi: {g['p_error']:.4f} of q in {g['cpu_s']} CPU s with "
              f"{g['particles']} particles ({g['source']}); psph's fastest at <= 1 %: "
              f"{h['best_at_1pct_cpu_s']:.1f} CPU s")
    print(f"wrote {jpath} and {ppath}")


if __name__ == "__main__":
    main()

"""Convergence of the landslide answers: run-out and the other collapse
metrics against the particle spacing dx and the time step, with the local softening law
of Eq. (17)-(19) and with its non-local regularisation (`material.plasticity.
regularisation`, psph/physics/softening.py), and their error against wall time.

For `collapse_saturated_psi0` and `collapse_dry` (Section 4.4), dx in {0.04, 0.04/sqrt 2,
0.02} (refinement ratio r = sqrt 2: 5,000, 10,000 and 20,000 particles) and dt in {1, 1/2,
1/4} of the scheme's largest step at that dx: the solid cap Eq. (41) (dry, the
projection); for TPI the scene's own 2e-5 s (the paper's; 82 % of TPI's bound under
gravity, `limits.tpi_gain_dt_limit`, 2.43e-5 s at alpha = 0.5, below the cap at every
dx); for explicit Eq. (42) and the undrained wave limit (only that step: about 4e-6 s at
dx = 0.04, 1e-6 s at 0.02, a million steps); "tpi-beta0" is TPI with Eq. (47) off
(`pressure.beta = 0`), for the storage's part in the answer. Every case runs on 2 ranks
to the scene's end (1.2 s saturated, 2 s dry).

For `retrogressive_k0_0.5` (Section 4.5): dx = 0.4 m (the paper's) and 0.4 sqrt 2 = 0.566 m
(half the particles), local and regularised with l_c = 1.2 m (3 dx and 2.1 dx; "regularised"
with the default exponent m = 2, "regularised-m1" with m = 1), each with the scene's own
pressure scheme and step (explicit at 4e-4 s with the symplectic step: "scene" in the
label), the full 40 s: slides and run-out side by side (25 min for the local case at 0.4 m
on 2 ranks; the regularised cases cost more, as the averaging's support holds (2 l_c / dx)^2
times more particles than the kernel's).

The dx series at a fixed dt fraction refine dt with dx for the dry runs and the
projection (the cap is proportional to dx) but not for TPI (2e-5 s at every dx): their
"order in dx" is of space and time together there, of space alone for TPI.

Per metric and series (a scene, scheme, law and dt fraction over the three dx, or a dx
over the three dt), `richardson` gives the observed order p = ln((f1 - f2) / (f2 - f3)) /
ln r and the extrapolated value f* = f3 + (f3 - f2) / (r^p - 1) when the differences
keep their sign (else no order: the series is not in its asymptotic range). A case's
error is its distance to the reference of its scene, scheme and law: the dx-extrapolated
run-out at the smallest dt fraction that has one, else the finest run.

    python bench/verification/convergence.py --quick      # CI-sized (a 1 x 0.5 m dry column)
    python bench/verification/convergence.py --smoke      # its coarsest local case to 0.05 s
    python bench/verification/convergence.py              # the full matrix (hours on 2 cores)
    python bench/verification/convergence.py --only 'psi0 tpi .* dt=1'   # a subset (regex)
    python bench/verification/convergence.py --only 'k0_0.5'   # the slope pairs
    python bench/verification/convergence.py --table-only # table and PNG from the JSON
    python bench/verification/convergence.py --table-only \
        --adopt 'retrogressive_k0_0.5 scene local dx=0.4 dt=1' runs/k05_cutoff
        # a case from a finished run of the case's scene (scene.toml value for value but
        # description, checkpoint and output; other snapshot times: last-snapshot metrics)

Prints a table, writes <out>/convergence[-quick|-smoke].json (one entry per case, kept
between runs: a case already measured is not run again unless --rerun) and draws
<out>/convergence[-quick|-smoke].png (run-out error against wall time, and run-out
against dx) and, with slope cases, <out>/convergence-slope.png (their last snapshots);
the runs go to <out>/convergence[-quick|-smoke]/.
"""

import argparse
import json
import math
import os
import platform
import re
import subprocess
import sys
import time
from datetime import date
from pathlib import Path

from psph.verify.convergence import series

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(__file__).resolve().parents[1] / "out"

DX = (0.04, 0.04 / math.sqrt(2.0), 0.02)
FRACTIONS = (1.0, 0.5, 0.25)
# the internal length of the regularised law, a material property in metres (the same at
# every dx): 1.5 dx at the coarsest spacing, 3 dx at the finest; the averaging's cost grows
# as (l_c / dx)^2 (at l_c = 0.1 m the finest quick case took 4.4x the local one)
L_C = 0.06
# the slope's internal length: 3 dx at 0.4 m, 2.1 dx at 0.566 m
SLOPE_L_C = 1.2
SLOPE_DX = (0.4, 0.4 * math.sqrt(2.0))
# the slope's laws: besides the default over-non-local average (m = 2), the plain one
# (m = 1), which softens a band on the fixed base alike at both spacings (docs/vv/
# convergence.md; bench/studies/nonlocal_sliding.py)
SLOPE_LAWS = ("local", "regularised", "regularised-m1")


def regularised(length: float, m: float | None = None) -> list[str]:
    """The --set of the non-local law with internal length `length` (m) and, if given,
    its over-non-local exponent m (else the default)."""
    exponent = "" if m is None else f", m={m}"
    return [f"material.plasticity.regularisation={{kind='nonlocal', length={length}"
            f"{exponent}}}"]


REGULARISED = regularised(L_C)
# the quick mode's column: 1 m x 0.5 m (a quarter of the Section 4.4 column's size) with
# a fifth of the cohesion (1 kPa peak, 0.2 residual), so that it collapses as the 2 m
# column does (critical height 4 c tan(45 + phi / 2) / gamma: 0.31 m here, 1.55 m there)
QUICK_SETS = ["particles.blocks=[{min=[0.0, 0.0], max=[1.0, 0.5]}]", "domain.max=[4.0, 1.0]",
              "material.plasticity.c=1.0e3", "material.plasticity.c_r=0.2e3",
              "time.end=0.5", "output.interval=0.05"]
QUICK_DX = (0.04, 0.04 / math.sqrt(2.0), 0.02)
METRICS = ("runout_m", "final_height_m", "back_scarp_m", "slides", "plastic_work_J_per_m",
           "excess_p_peak_Pa")
# read over the snapshots, not from the last one (`psph.verify.collapse`)
SNAPSHOT_METRICS = ("slides", "slide_times_s", "excess_p_peak_Pa")


def slug(label: str) -> str:
    """A case's directory name under <out>/convergence[-quick|-smoke]/."""
    return re.sub(r"[^A-Za-z0-9.=-]+", "_", label)


def largest_dt(scene_name: str, scheme: str, dx: float, sets: list[str]) -> float:
    """The scheme's largest stable step at dx (see the module docstring)."""
    from psph.config.load import load_scene
    from psph.physics.limits import (
        fluid_dt_limit,
        solid_dt_limit,
        tpi_gain_dt_limit,
        undrained_dt_limit,
    )

    own = load_scene(scene_name).time.dt
    if scheme == "scene":  # the scene's own scheme and step
        return own
    # a small time.dt: the scene's own may be beyond this scheme's limits
    scene = load_scene(scene_name, sets + [f"particles.dx={dx!r}", "time.dt=1e-9"])
    cap = solid_dt_limit(scene)
    if scheme.startswith("tpi"):  # the scene's (the paper's) step, inside TPI's bound
        return min(cap, tpi_gain_dt_limit(scene), own or math.inf)
    if scheme == "explicit":
        return min(cap, fluid_dt_limit(scene), undrained_dt_limit(scene))
    return cap


def cases(quick: bool) -> list[dict]:
    """Every case: label, scene, --set overrides and its coordinates (dx, dt fraction,
    scheme, law)."""
    out = []
    if quick:
        plan = [("collapse_dry", "dry", QUICK_SETS, QUICK_DX, (1.0,))]
    else:
        plan = [("collapse_saturated_psi0", s, [], DX, (1.0,) if s == "explicit" else FRACTIONS)
                for s in ("tpi", "tpi-beta0", "projection", "explicit")]
        plan.append(("collapse_dry", "dry", [], DX, FRACTIONS))
        plan.append(("retrogressive_k0_0.5", "scene", [], SLOPE_DX, (1.0,)))
    for scene, scheme, base, dxs, fractions in plan:
        sets = list(base)
        if scheme == "projection":
            sets += ["pressure.scheme='projection'", "pressure.tolerance=1e-6"]
        elif scheme == "explicit":
            sets += ["pressure.scheme='explicit'"]
        elif scheme == "tpi-beta0":  # Eq. (47) off: the suction storage's part in the answer
            sets += ["pressure.beta=0.0"]
        slope = scene.startswith("retrogressive")
        for law in SLOPE_LAWS if slope else ("local", "regularised"):
            length = SLOPE_L_C if slope else L_C
            law_sets = sets + {"local": [], "regularised": regularised(length),
                               "regularised-m1": regularised(length, 1.0)}[law]
            for dx in dxs:
                top = largest_dt(scene, scheme, dx, law_sets)
                for f in fractions:
                    dt = f * top
                    short = scene.replace("collapse_saturated_", "").replace("collapse_", "")
                    out.append({
                        "label": f"{short} {scheme} {law} dx={dx:.4g} dt={f:g}",
                        "scene": scene, "scheme": scheme, "law": law, "dx": dx,
                        "dt_fraction": f, "dt": dt,
                        "sets": law_sets + [f"particles.dx={dx!r}", f"time.dt={dt!r}"]})
    return out


CASE_KEYS = ("label", "scene", "scheme", "law", "dx", "dt_fraction", "dt", "sets")


def run_case(case: dict, out: Path) -> dict:
    """One case on 2 ranks; its metrics from summary.json, or how it failed."""
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")
    cmd = ["mpirun", "-n", "2", sys.executable, "-m", "psph", "run", case["scene"], "--out",
           str(out), "--quiet"]
    for s in case["sets"]:
        cmd += ["--set", s]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, cwd=ROOT, stderr=subprocess.PIPE, text=True)
    entry = {k: case[k] for k in CASE_KEYS}
    entry.update(exit_code=proc.returncode, bench_wall_s=time.perf_counter() - t0)
    summary = out / "summary.json"
    if proc.returncode != 0 or not summary.is_file():
        lines = (proc.stderr or "").strip().splitlines()
        # psph's own line (exit 2 or 3 names the key, or the step, particle and field);
        # mpirun appends its banner after it
        entry["failure"] = [s for s in lines if s.startswith("psph")][-2:] or lines[-1:]
        return entry
    return read_metrics(entry, out)


def adopt_run(case: dict, run: Path) -> dict:
    """A case from a finished run directory (`--adopt LABEL DIR`) instead of running it
    again: only when the scene that run wrote (DIR/scene.toml) is the case's scene with its
    overrides, value for value, except `description`, `checkpoint` and `output`
    (`psph.app.restart_rules.physics_difference` with the same `time.end` and `decomposition`),
    and the run finished; SystemExit otherwise. A run continued from a checkpoint (the same
    physics: the restart rules) is adopted without a wall time. With other `output`
    (snapshot times) only the last snapshot's metrics are taken: the slides and the excess
    p's peak are read over the snapshots (`SNAPSHOT_METRICS`). The code that ran it is not
    checked: adopt a run made with the code of the other cases."""
    from psph.app.restart_rules import physics_difference
    from psph.config.load import load_scene, run_scene, to_toml
    from psph.errors import SceneError

    run = run.resolve()
    scene = load_scene(case["scene"], case["sets"])
    try:
        written = run_scene(run)
        summary = json.loads((run / "summary.json").read_text())
        diff = physics_difference(to_toml(written), scene, f"{run}/scene.toml")
    except (OSError, SceneError, ValueError) as err:
        raise SystemExit(f"--adopt: {run}: {err}") from None
    if diff is None:
        for key in ("time", "decomposition"):
            if getattr(written, key) != getattr(scene, key):
                diff = key, getattr(scene, key), getattr(written, key)
    if diff is not None:
        key, want, ran = diff
        raise SystemExit(f"--adopt: {run} ran {key} = {ran!r}, the case '{case['label']}' "
                         f"has {want!r}")
    if summary.get("status") != "finished":
        raise SystemExit(f"--adopt: {run} did not finish (status {summary.get('status')!r})")
    entry = {k: case[k] for k in CASE_KEYS}
    entry.update(exit_code=0, adopted_from=str(run))
    entry = read_metrics(entry, run)
    if "restarted_from" in summary:
        # continued from a checkpoint (bitwise the uninterrupted run, tests/
        # test_parallel_runs.py): the physics is the case's, the wall time only the last leg's
        entry.update(wall_s=None, restarted_from=summary["restarted_from"])
        if first_snapshot_time(run / "particles.h5") > 0.0:
            # continued into another directory: its snapshots start at the checkpoint
            for k in SNAPSHOT_METRICS:
                entry.pop(k, None)
            entry["snapshot_metrics"] = "not adopted: the snapshots start after t = 0"
    if written.output != scene.output:
        for k in SNAPSHOT_METRICS:
            entry.pop(k, None)
        entry["snapshot_metrics"] = "not adopted: other snapshot times"
    return entry


def read_metrics(entry: dict, out: Path) -> dict:
    """entry with the wall time, steps and `metrics.collapse` of OUT/summary.json."""
    s = json.loads((out / "summary.json").read_text())
    m = s.get("metrics", {})
    col = m.get("collapse", {})
    entry.update(wall_s=s["wall_time_s"], steps=s["steps"], particles=s["particles"],
                 run_dir=str(out.resolve()))
    for k in METRICS + ("toe_m", "slide_times_s"):
        if k in col:
            entry[k] = col[k]
    if "excess_p_peak_Pa" not in entry and "pressure_quality" in m:
        extremes = m["pressure_quality"].get("extremes", {})
        if "max" in extremes:
            entry["excess_p_peak_Pa"] = extremes["max"].get("value")
    return entry


def errors(report: list[dict], rich: list[dict], metric: str = "runout_m") -> None:
    """Each case's relative distance to its scene, scheme and law's reference (in place:
    `<metric>_error`, `reference`)."""
    for e in report:
        if metric not in e:
            continue
        same = [s for s in rich if (s["scene"], s["scheme"], s["law"], s["in"])
                == (e["scene"], e["scheme"], e["law"], "dx") and s["extrapolated"] is not None]
        if same:
            ref = min(same, key=lambda s: float(s["at"].split("=")[1]))
            value, kind = ref["extrapolated"], f"extrapolated in dx at {ref['at']}"
        else:
            group = [g for g in report if metric in g and (g["scene"], g["scheme"], g["law"])
                     == (e["scene"], e["scheme"], e["law"])]
            finest = min(group, key=lambda g: (g["dx"], g["dt_fraction"]))
            value, kind = finest[metric], f"finest run ({finest['label']})"
        e[f"{metric}_error"] = abs(e[metric] - value) / abs(value) if value else None
        e["reference"] = kind


def table(report: list[dict], rich: list[dict]) -> None:
    print(f"{'case':58s} {'exit':>4s} {'wall s':>8s} {'particles':>9s} {'runout m':>9s} "
          f"{'error':>7s} {'height m':>8s} {'scarp m':>8s} {'slides':>6s} {'W_p J/m':>9s}")
    def num(e, k, fmt):
        if e.get(k) is None:  # the width of fmt, e.g. "8.1f" -> 8
            return "-".rjust(int(re.match(r"\d*", fmt).group() or 0))
        return format(e[k], fmt)

    for e in report:
        print(f"{e['label']:58s} {e['exit_code']:4d} {num(e, 'wall_s', '8.1f')} "
              f"{num(e, 'particles', '9d')} {num(e, 'runout_m', '9.4f')} "
              f"{num(e, 'runout_m_error', '7.2%')} {num(e, 'final_height_m', '8.3f')} "
              f"{num(e, 'back_scarp_m', '8.3f')} {num(e, 'slides', '6d')} "
              f"{num(e, 'plastic_work_J_per_m', '9.4g')}")
    print("\nrun-out series (coarse to fine): observed order, extrapolated value, change "
          "between the two finest")
    for s in rich:
        order = f"{s['order']:.2f}" if s["order"] is not None else "-"
        ext = f"{s['extrapolated']:.4f}" if s["extrapolated"] is not None else "-"
        vals = " ".join(f"{v:.4f}" for v in s["values"])
        change = f"{s['finest_change']:.2%}" if s["finest_change"] is not None else "-"
        print(f"  {s['scene']:24s} {s['scheme']:10s} {s['law']:14s} in {s['in']} "
              f"{s['at']:10s} {vals}  p = {order:5s} f* = {ext:8s} finest change {change}")


def plot(report: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8))
    marker = {"local": "o", "regularised": "s", "regularised-m1": "^"}
    groups = sorted({(e["scene"], e["scheme"], e["law"]) for e in report if "runout_m" in e})
    for g in groups:
        rows = [e for e in report if (e["scene"], e["scheme"], e["law"]) == g
                and e.get("runout_m_error")]  # the reference run itself (0) left out
        label = f"{g[0].replace('collapse_', '')} {g[1]} {g[2]}"
        rows = [e for e in rows if e.get("wall_s") is not None]  # restarted: no wall time
        if rows:
            ax.loglog([e["wall_s"] for e in rows],
                      [e["runout_m_error"] for e in rows], marker[g[2]],
                      label=label, alpha=0.8)
        top = sorted((e for e in report if (e["scene"], e["scheme"], e["law"]) == g
                      and "runout_m" in e and e["dt_fraction"] == 1.0
                      and g[0].startswith("collapse")), key=lambda e: e["dx"])
        if top:
            bx.plot([e["dx"] for e in top], [e["runout_m"] for e in top],
                    "-" + marker[g[2]], label=label)
    ax.set_xlabel("wall time on 2 ranks (s)")
    ax.set_ylabel("run-out error against the reference")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    bx.set_xlabel("dx (m)")
    bx.set_ylabel("collapse run-out (m), largest dt")
    bx.grid(True, alpha=0.3)
    bx.legend(fontsize=7)
    fig.suptitle(f"psph convergence of the run-out ({date.today()}, "
                 f"{platform.node()})")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def first_snapshot_time(path: Path) -> float:
    """Time of the first snapshot in a run's particles.h5."""
    import h5py

    with h5py.File(path, "r") as f:
        return float(f["snapshots"][sorted(f["snapshots"])[0]].attrs["time"])


def last_snapshot(path: Path) -> dict:
    """x, eps_p and time of the last snapshot in a run's particles.h5."""
    import h5py

    with h5py.File(path, "r") as f:
        g = f["snapshots"][sorted(f["snapshots"])[-1]]  # the order of read_snapshots
        return {"x": g["x"][...], "eps_p": g["eps_p"][...], "time": float(g.attrs["time"])}


def plot_slopes(report: list[dict], path: Path) -> None:
    """The slope cases' last snapshots, one panel each (equivalent plastic strain), with
    their slides and toe: the pictures of the slope pair."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = sorted((e for e in report if e["scene"].startswith("retrogressive")
                   and e.get("exit_code") == 0 and "toe_m" in e
                   and (Path(e.get("run_dir", "")) / "particles.h5").is_file()),
                  key=lambda e: (e["law"], e["dx"]))
    if not rows:
        return
    fig, axes = plt.subplots(len(rows), 1, figsize=(12, 1.5 * len(rows) + 0.8),
                             squeeze=False, sharex=True, layout="constrained")
    for ax, e in zip(axes[:, 0], rows, strict=True):
        s = last_snapshot(Path(e["run_dir"]) / "particles.h5")
        sc = ax.scatter(s["x"][:, 0], s["x"][:, 1], c=s["eps_p"], s=0.5, vmin=0.0, vmax=2.0,
                        cmap="viridis", rasterized=True)
        ax.axvline(e["toe_m"], color="r", lw=0.8)
        times = ", ".join(f"{t:.0f}" for t in e.get("slide_times_s") or [])
        slides = e.get("slides", "?")
        ax.set_title(f"{e['law']}, dx = {e['dx']:.3g} m: {slides} slides ({times} s), "
                     f"toe {e['toe_m']:.0f} m, run-out {e['runout_m']:.0f} m, "
                     f"t = {s['time']:.0f} s", fontsize=9)
        ax.set_xlim(0.0, max(r["toe_m"] for r in rows) + 20.0)
        ax.set_ylim(0.0, 22.0)
        ax.set_ylabel("y (m)")  # vertical scale exaggerated
    axes[-1, 0].set_xlabel("x (m); vertical scale exaggerated")
    fig.colorbar(sc, ax=axes[:, 0], label="equivalent plastic strain", shrink=0.8)
    laws = ", ".join(sorted({e["law"] for e in rows}))
    fig.suptitle(f"retrogressive_k0_0.5: {laws} (l_c = {SLOPE_L_C} m; regularised-m1: m = 1;"
                 f" {date.today()}, {platform.node()})", fontsize=10)
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> int:
    global OUT, QUICK_DX
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the CI-sized dry column")
    ap.add_argument("--smoke", action="store_true",
                    help="the CI-sized column's coarsest local case to 0.05 s (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the runs, the JSON and the PNG (default bench/out)")
    ap.add_argument("--only", help="run only the cases whose label matches this regex")
    ap.add_argument("--rerun", action="store_true", help="run cases already in the JSON")
    ap.add_argument("--table-only", action="store_true", help="no runs: table and PNG")
    ap.add_argument("--adopt", action="append", nargs=2, default=[], metavar=("LABEL", "DIR"),
                    help="take a case from a finished run of the same scene and overrides")
    args = ap.parse_args(argv)
    OUT = args.out
    OUT.mkdir(parents=True, exist_ok=True)
    name = "convergence-quick" if args.quick else "convergence"
    if args.smoke:
        args.quick, name, QUICK_DX = True, "convergence-smoke", QUICK_DX[:1]
        QUICK_SETS[QUICK_SETS.index("time.end=0.5")] = "time.end=0.05"
        args.only = args.only or " local "
    path = OUT / f"{name}.json"
    old = json.loads(path.read_text())["cases"] if path.is_file() else []
    by_label = {e["label"]: e for e in old}
    todo = cases(args.quick)
    by_case = {c["label"]: c for c in todo}
    for label, run in args.adopt:
        if label not in by_case:
            raise SystemExit(f"--adopt: no case labelled '{label}'")
        if args.rerun:
            raise SystemExit("--adopt and --rerun: --rerun would run the adopted case again")
        by_label[label] = adopt_run(by_case[label], Path(run))
    if args.only:
        todo = [c for c in todo if re.search(args.only, c["label"])]
    if not args.table_only:
        for c in todo:
            done = by_label.get(c["label"], {})
            if not args.rerun and done.get("exit_code") == 0 and done.get("sets") == c["sets"]:
                continue  # the same case (the same overrides, l_c among them) measured
            print(f"[convergence] {c['label']} ...", flush=True)
            by_label[c["label"]] = run_case(c, OUT / name / slug(c["label"]))
            report = {"date": str(date.today()), "machine": platform.node(),
                      "cases": list(by_label.values())}
            path.write_text(json.dumps(report, indent=1))
    report = list(by_label.values())
    rich = series(report)
    errors(report, rich)
    table(report, rich)
    path.write_text(json.dumps({"date": str(date.today()), "machine": platform.node(),
                                "l_c_m": L_C, "slope_l_c_m": SLOPE_L_C, "cases": report,
                                "series": rich}, indent=1))
    plot(report, OUT / f"{name}.png")
    plot_slopes(report, OUT / f"{name}-slope.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())

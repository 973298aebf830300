"""Stability of the pressure projection against its stable step.

Each column runs with `pressure.scheme = "projection"` at dt = f x the step validation
accepts for it, the solid cap Eq. (41), f from 0.25 to 2, after the kick ("symplectic",
the projection's default) and in the one-sweep step ("euler", which validation refuses
with the projection; forced here with pressure.allow_unstable), on 1 and 2 ranks, to
the scene's end time. A run is stable when it exits 0
and its pore pressure stays within [-0.1 q, 1.2 q] in every history row (the CI
column at the one-sweep step's Eq. (41) ran to its end with p at 13 q: the exit code
alone does not tell). The error is max |p - p_a| / q over the scene's T_v.

Columns: "paper" (`terzaghi_tpi` with the projection: Section 4.1, dx = 0.01 m, k = 2e-4,
C_CFL^s = 0.1, to T_v = 1), "default" (`terzaghi`, the default run: the same column at
C_CFL^s = 0.4, CG tolerance 1e-6), "ci" (the paper's at dx = 0.02 m, k = 8e-4, the
tests' size) and "geotaichi" (`terzaghi_undrained`: GeoTaichi's start, dx = 0.02 m,
100 particles).

    .venv/bin/python bench/verification/projection_stability.py --jobs 2         # ~30 min
    .venv/bin/python bench/verification/projection_stability.py --full --jobs 2  # hours
    .venv/bin/python bench/verification/projection_stability.py --only 'ci|geotaichi' --jobs 2
    .venv/bin/python bench/verification/projection_stability.py --plot-only   # the record
    .venv/bin/python bench/verification/projection_stability.py --quick
        # GeoTaichi's column after the kick at the stable step to T_v = 0.01

Finished cases are appended to docs/data/projection_stability.jsonl (committed), so a
stopped sweep resumes, on this machine or another, and the docs' table is built from every
recorded row. Prints the table, writes <out>/projection_stability.json, .png and .md
(the docs' table).
"""

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from datetime import date
from pathlib import Path

from psph.config.load import load_scene
from psph.physics.limits import solid_dt_limit

OUT = Path(__file__).resolve().parents[1] / "out"
RECORD = Path(__file__).resolve().parents[2] / "docs" / "data" / "projection_stability.jsonl"
Q = 1.0e4
FACTORS = (0.25, 0.5, 1.0, 1.5, 2.0)
COLUMNS = {  # cheapest first
    "geotaichi": ("terzaghi_undrained", []),
    "ci": ("terzaghi_tpi", ["particles.dx=0.02", "material.k=8e-4",
                            "verification.tv=[0.05, 0.1, 0.2, 0.5, 1.0]"]),
    "paper": ("terzaghi_tpi", []),
    # the default run's scene: the same column, C_CFL^s = 0.4, CG tolerance 1e-6
    "default": ("terzaghi", []),
}
COMMON = ["pressure.scheme='projection'", "output.interval=0.0", "output.times=[]",
          "checkpoint.at_end=false", "checkpoint.wall_seconds=0"]


def stable_step(column: str) -> float:
    """The projection's stable step validation enforces: Eq. (41) (the one-sweep step is
    refused with the projection at any dt; it runs here forced)."""
    name, extra = COLUMNS[column]
    return solid_dt_limit(load_scene(name, extra + COMMON))


def cases(full: bool = False) -> list[dict]:
    """Every column x integrator x FACTORS x ranks 1, 2 with `full`; by default the
    paper's column and the default scene (1000 particles, to 1.7 s) only at f >= 1 and
    on 2 ranks only at f = 1 (f = 0.25 after the kick there is 560k steps), and the
    refused one-sweep step on 1 rank (it is bitwise the same on 2: tests/test_mpi.py)."""
    out = []
    for column in COLUMNS:
        for integrator in ("symplectic", "euler"):
            cap = stable_step(column)
            for f in FACTORS:
                for ranks in (1, 2):
                    big = column in ("paper", "default")
                    if not full and (
                            (big and f < 1.0)
                            or (column == "default" and (integrator == "euler" or f < 1.0))
                            or (ranks == 2 and (integrator == "euler" or
                                                (big and f != 1.0)))):
                        continue
                    out.append({"label": f"{column} {integrator} f={f:g} ranks={ranks}",
                                "column": column, "integrator": integrator, "factor": f,
                                "ranks": ranks, "dt": f * cap, "cap": cap})
    return out


def run_case(case: dict) -> dict:
    """One run in a subprocess (mpirun for 2 ranks): exit code, failure line, error, the
    pore-pressure range over the history, wall time."""
    name, extra = COLUMNS[case["column"]]
    sets = extra + COMMON + [f"time.integrator='{case['integrator']}'",
                             f"time.dt={case['dt']!r}",
                             "time.allow_dt_above_solid_limit=true",
                             "pressure.allow_unstable=true"]
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "psph", "run", name, "--out", tmp, "--quiet"]
        for s in sets:
            cmd += ["--set", s]
        if case["ranks"] > 1:
            cmd = ["mpirun", "-n", str(case["ranks"])] + cmd
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True,
                              env=dict(os.environ, NUMBA_NUM_THREADS="1",
                                       OMPI_MCA_mpi_yield_when_idle="1"))
        wall = time.perf_counter() - t0
        result = dict(case, rc=proc.returncode, wall_s=wall, error=None, p_max=None,
                      p_min=None, failure=None)
        m = re.search(r"numerical failure: (step \d+, t = [0-9.e-]+ s)", proc.stderr)
        if m:
            result["failure"] = m.group(1)
        hist = Path(tmp) / "history.csv"
        if hist.exists():
            lines = hist.read_text().split()
            keys = lines[0].split(",")
            rows = [dict(zip(keys, map(float, ln.split(",")), strict=True))
                    for ln in lines[1:]]
            result["p_max"] = max(r["p_max"] for r in rows)
            result["p_min"] = min(r["p_min"] for r in rows)
        summ = Path(tmp) / "summary.json"
        if summ.exists():
            errors = json.loads(summ.read_text()).get("errors") or {}
            result["error"] = errors.get("max_abs_p_error_over_q")
    result["stable"] = stable(result)
    return result


def stable(r: dict) -> bool:
    """Exit 0 and p within [-0.1 q, 1.2 q] in every history row (the loading ramp's
    undrained overshoot reaches 1.11 q on the CI column; a growing mode leaves it)."""
    return bool(r["rc"] == 0 and r["p_max"] is not None and r["p_max"] <= 1.2 * Q
                and r["p_min"] >= -0.1 * Q)


def table(rows: list[dict]) -> str:
    head = (f"{'column':10s} {'integrator':10s} {'f':>5s} {'ranks':>5s} {'dt (s)':>10s} "
            f"{'outcome':>8s} {'error/q':>8s} {'p_max/q':>8s} {'p_min/q':>8s} {'wall s':>7s}"
            "  failure")
    lines = [head, "-" * len(head)]
    for r in rows:
        err = "-" if r["error"] is None else f"{r['error']:.4f}"
        pmx = "-" if r["p_max"] is None else f"{r['p_max'] / Q:.3f}"
        pmn = "-" if r["p_min"] is None else f"{r['p_min'] / Q:.3f}"
        lines.append(f"{r['column']:10s} {r['integrator']:10s} {r['factor']:5g} "
                     f"{r['ranks']:5d} {r['dt']:10.3e} "
                     f"{'runs' if r['stable'] else 'FAILS':>8s} {err:>8s} {pmx:>8s} {pmn:>8s} "
                     f"{r['wall_s']:7.1f}  {r['failure'] or ''}")
    return "\n".join(lines)


def markdown(rows: list[dict]) -> str:
    """The table for the docs (docs/vv/projection_stability.md)."""
    lines = ["| column | integrator | f | ranks | dt (s) | outcome | max error / q | "
             "p max / q | p min / q | wall s | exit 3 at |", "|---" * 11 + "|"]
    for r in rows:
        err = "–" if r["error"] is None else f"{r['error']:.4f}"
        lines.append(
            f"| {r['column']} | {r['integrator']} | {r['factor']:g} | {r['ranks']} | "
            f"{r['dt']:.3g} | {'runs' if r['stable'] else '**fails**'} | {err} | "
            f"{r['p_max'] / Q:.3g} | {r['p_min'] / Q:.3g} | {r['wall_s']:.0f} | "
            f"{r['failure'] or '–'} |")
    return "\n".join(lines) + "\n"


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = sorted({(r["column"], r["integrator"]) for r in rows})
    fig, ax = plt.subplots(figsize=(7.5, 0.6 * len(groups) + 1.6))
    for y, g in enumerate(groups):
        for r in rows:
            if (r["column"], r["integrator"]) != g:
                continue
            dy = -0.12 if r["ranks"] == 1 else 0.12
            ax.scatter(r["factor"], y + dy, marker="o" if r["stable"] else "x", s=60,
                       color="tab:green" if r["stable"] else "tab:red")
    ax.axvline(1.0, color="0.4", lw=1, ls="--")
    ax.set_yticks(range(len(groups)), [f"{c}, {i}" for c, i in groups])
    ax.set_xlabel("dt / the projection's stable step of validation")
    ax.set_title("projection: runs (o) and fails (x); 1 rank below, 2 ranks above the line")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", help="regular expression over the case labels")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--plot-only", action="store_true",
                    help="the table and picture from the record, running nothing")
    ap.add_argument("--full", action="store_true", help="every factor on 1 and 2 ranks")
    ap.add_argument("--record", type=Path, default=RECORD,
                    help="the rows measured so far, one JSON line per case (default: the "
                         "docs' record, so that a sweep resumes on any machine)")
    ap.add_argument("--quick", action="store_true",
                    help="one case, GeoTaichi's column after the kick at f = 1 on 1 rank to "
                         "T_v = 0.01, recorded in <out>/projection_stability-quick.jsonl "
                         "(a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON, PNG and table (default bench/out)")
    args = ap.parse_args()
    if args.quick:
        args.only = "^geotaichi symplectic f=1 ranks=1$"
        COMMON.append("verification.tv=[0.01]")
        if args.record == RECORD:
            args.record = args.out / "projection_stability-quick.jsonl"
    args.out.mkdir(parents=True, exist_ok=True)
    done = {}
    if args.record.exists():
        for line in args.record.read_text().splitlines():
            r = json.loads(line)
            done[r["label"]] = r
    if not args.plot_only:
        todo = [c for c in cases(args.full) if not args.only or re.search(args.only, c["label"])]
        rest = [c for c in todo if c["label"] not in done]
        print(f"{len(todo) - len(rest)} of {len(todo)} cases in {args.record}", flush=True)
        with ThreadPoolExecutor(args.jobs) as pool, args.record.open("a") as log:
            for r in pool.map(run_case, rest):
                r["recorded"] = f"{date.today().isoformat()} on {platform.node()}"
                done[r["label"]] = r
                log.write(json.dumps(r) + "\n")
                log.flush()
                print(table([r]).splitlines()[-1], flush=True)
    order = {c["label"]: i for i, c in enumerate(cases(full=True))}
    rows = sorted(done.values(), key=lambda r: order.get(r["label"], len(order)))
    for r in rows:
        r["stable"] = stable(r)
    (args.out / "projection_stability.json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.node(), "rows": rows},
        indent=1))
    print(table(rows))
    plot(rows, args.out / "projection_stability.png")
    (args.out / "projection_stability.md").write_text(markdown(rows))
    print(f"wrote {args.out}/projection_stability.json, .png, .md (every recorded row)")


if __name__ == "__main__":
    main()

"""About ten million particles on this machine: the dry collapse at
dx = 0.0009 m (9.9M particles) on 2 ranks sets up, runs 100 steps, writes a snapshot and a
checkpoint, and restarts from it for 100 more; then the same scene's set-up (one step, no
checkpoint) on 1, 2 and 4 ranks (4 oversubscribed on 2 cores) shows the peak memory per
rank against the rank count.

    python bench/performance/large_run.py                 # dx 0.0009: ~25 min, 12 GB at 1 rank
    python bench/performance/large_run.py --dx 0.004      # a rehearsal at 0.5M particles (a minute)
    python bench/performance/large_run.py --plot-only
    python bench/performance/large_run.py --scene collapse_3d --dx 0.0058   # 2.0M in 3D
    python bench/performance/large_run.py --scene collapse_3d --dx 0.0034 --steps 2
        # 10M in 3D: the same protocol with 2 steps a run (100 take hours here)
    python bench/performance/large_run.py --quick         # dx 0.04, 2 steps (a smoke check)

Each case is one `mpirun -n R python -m psph run collapse_dry`; its summary.json gives the
set-up seconds, the seconds per step of the time loop (the snapshot and checkpoint writes
are in the loop: `stage_seconds` splits them out), the peak resident memory of every rank
(getrusage) and particle-steps/s/core. Prints a table, writes <out>/large_run[...].json and
.png; the run directories (GBs) are removed.
"""

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from datetime import date
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "bench" / "out"
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none", "NUMBA_NUM_THREADS": "1"}
STEPS = 100


SCENE = "collapse_dry"  # `--scene`
# collapse_3d's floor is a surface lined with boundary particles, which
# every rank builds whole (three rows of the floor's area / dx^2: 2.7 M at dx = 0.0058);
# the scale run keeps the box's mirror floor it was measured with
SCENE_SETTINGS = {"collapse_3d": ["boundaries.surfaces=[]",
                                  "boundaries.bottom={motion='fixed'}"]}


def solid_dt(dx: float) -> float:
    from psph.config.load import load_scene
    from psph.solver.stepping import time_stepping

    return time_stepping(load_scene(SCENE, [f"particles.dx={dx}",
                                            *SCENE_SETTINGS.get(SCENE, [])])).dt_main


def mpirun(label: str, ranks: int, out: Path, *settings: str, restart: bool = False) -> dict:
    cmd = ["mpirun", "-n", str(ranks), sys.executable, "-m", "psph", "run", SCENE,
           "--out", str(out), "--quiet"]
    for s in [*SCENE_SETTINGS.get(SCENE, []), *settings]:
        cmd += ["--set", s]
    if restart:
        cmd += ["--restart", str(out / "checkpoint.h5")]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=ROOT, env={**os.environ, **MPI_ENV}, capture_output=True,
                       text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr[-2000:]}")
    s = json.loads((out / "summary.json").read_text())
    stages = s.get("stage_seconds", {})
    steps = s["steps_this_run"]
    row = {"case": label, "ranks": ranks, "particles": s["particles"],
           "setup_s": s["setup_s"], "loop_s": s["loop_s"], "steps": steps,
           "s_per_step": s["loop_s"] / max(steps, 1),
           "particle_steps_per_s_per_core": s["particle_steps_per_second_per_core"],
           "peak_rss_bytes_per_rank": s["memory"]["peak_rss_bytes_per_rank"],
           "state_bytes_per_owned_particle": s["memory"]["state_bytes_per_owned_particle"],
           "snapshot_s": sum(v for k, v in stages.items() if "snapshot" in k),
           "checkpoint_s": sum(v for k, v in stages.items() if "checkpoint" in k),
           "mpirun_wall_s": wall, "status": s["status"]}
    print(f"  {label}: {ranks} rank(s), {row['particles']:,} particles, set-up "
          f"{row['setup_s']:.1f} s, {row['s_per_step']:.2f} s/step, peak "
          f"{max(row['peak_rss_bytes_per_rank']) / 2**30:.2f} GiB/rank", flush=True)
    return row


def measure(dx: float, setup_only: bool = False) -> list[dict]:
    dt = solid_dt(dx)
    end = STEPS * dt * (1 - 1e-9)
    base = OUT / f"large_run_{SCENE}"
    shutil.rmtree(base, ignore_errors=True)
    rows = []
    if setup_only:
        return rows + setup_rows(dx, base)
    run = base / "run"
    rows.append(mpirun(f"run {STEPS} steps + snapshot + checkpoint", 2, run,
                       f"particles.dx={dx}", f"time.end={end!r}", f"output.interval={end!r}"))
    rows.append(mpirun(f"restart, {STEPS} more steps", 2, run, f"particles.dx={dx}",
                       f"time.end={2 * end!r}",
                       f"output.interval={end!r}", restart=True))
    shutil.rmtree(run, ignore_errors=True)
    return rows + setup_rows(dx, base)


def setup_rows(dx: float, base: Path) -> list[dict]:
    """Set-up and one step on 1, 2 and 4 ranks (peak memory and set-up time)."""
    rows = []
    for ranks in (1, 2, 4):
        out = base / f"setup_{ranks}"
        rows.append(mpirun("set-up + 1 step", ranks, out, f"particles.dx={dx}",
                           "time.end=1e-12", "checkpoint.at_end=false"))
        shutil.rmtree(out, ignore_errors=True)
    return rows


def table(rows: list[dict]) -> None:
    one = [r for r in rows if r["case"].startswith("set-up") and r["ranks"] == 1]
    peak1 = max(one[0]["peak_rss_bytes_per_rank"]) if one else float("nan")
    print(f"{'case':<40s} {'ranks':>5s} {'particles':>11s} {'set-up s':>8s} "
          f"{'s/step':>7s} {'p-steps/s/core':>14s} {'peak GiB per rank':>24s} {'/1 rank':>7s}")
    for r in rows:
        peaks = r["peak_rss_bytes_per_rank"]
        print(f"{r['case']:<40s} {r['ranks']:5d} {r['particles']:11,d} {r['setup_s']:8.1f} "
              f"{r['s_per_step']:7.2f} {r['particle_steps_per_s_per_core']:14,.0f} "
              f"{' '.join(f'{p / 2**30:.2f}' for p in peaks):>24s} "
              f"{max(peaks) / peak1:7.2f}")


def plot(rows: list[dict], stem: str = "large_run") -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sel = [r for r in rows if r["case"].startswith("set-up")]
    ranks = [r["ranks"] for r in sel]
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].plot(ranks, [max(r["peak_rss_bytes_per_rank"]) / 2**30 for r in sel], "o-",
               label="largest rank")
    p1 = max(sel[0]["peak_rss_bytes_per_rank"]) / 2**30
    ax[0].plot(ranks, [p1 / r for r in ranks], "k--", label="1/P of 1 rank")
    ax[1].plot(ranks, [r["setup_s"] for r in sel], "o-", label="set-up s")
    ax[1].plot(ranks, [sel[0]["setup_s"] / r for r in ranks], "k--", label="1/P of 1 rank")
    ax[0].set(xlabel="ranks", ylabel="peak resident memory per rank (GiB)")
    ax[1].set(xlabel="ranks (4 share 2 cores)", ylabel="set-up time (s)")
    for a in ax:
        a.set_xticks(ranks)
        a.grid(True, alpha=0.3)
        a.legend()
    fig.suptitle(f"bench/performance/large_run.py, {SCENE}, {sel[0]['particles']:,} "
                 "particles, "
                 f"{date.today()}, {platform.node()}")
    fig.tight_layout()
    path = OUT / f"{stem}.png"
    fig.savefig(path, dpi=110)
    return path


def main(argv: list[str] | None = None) -> int:
    global SCENE, STEPS, OUT
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dx", type=float, default=0.0009)
    ap.add_argument("--scene", default="collapse_dry",
                    help="a built-in scene (default collapse_dry; collapse_3d for 3D)")
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--steps", type=int, default=100,
                    help="steps of the run and of the restart (default 100)")
    ap.add_argument("--setup-only", action="store_true",
                    help="only the set-up and one step on 1, 2 and 4 ranks (the memory and "
                    "set-up rows; a scene too large to run 200 steps here)")
    ap.add_argument("--quick", action="store_true",
                    help="dx = 0.04 m and 2 steps a run (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the runs (removed after), the JSON and the PNG "
                         "(default bench/out)")
    args = ap.parse_args(argv)
    if args.quick:
        args.dx, args.steps = 0.04, 2
    SCENE = args.scene
    STEPS = args.steps
    OUT = args.out
    OUT.mkdir(parents=True, exist_ok=True)
    stem = "large_run" if SCENE == "collapse_dry" else f"large_run_{SCENE}"
    if args.setup_only:
        stem += "_setup"
    elif args.steps != 100:
        stem += f"_{args.steps}steps"
    path = OUT / f"{stem}.json"
    if args.plot_only:
        rows = json.loads(path.read_text())["rows"]
    else:
        rows = measure(args.dx, args.setup_only)
        path.write_text(json.dumps({"date": str(date.today()), "machine": platform.node(),
                                    "cpus": os.cpu_count(), "scene": SCENE, "dx": args.dx,
                                    "rows": rows},
                                   indent=1) + "\n")
    table(rows)
    print(f"wrote {path} and {plot(rows, stem)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

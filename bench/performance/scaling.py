"""Strong scaling 1 -> 2 ranks at N ~ 20k, 100k, 400k, and weak scaling (50k per rank),
of the coupled elastic TPI step (the throughput bench's block, slabs along its long side).

    python bench/performance/scaling.py            # drives `mpirun -n R python <this> --worker`
    python bench/performance/scaling.py --quick    # 2k and 4k particles, few steps (a smoke check)
    python bench/performance/scaling.py --plot-only

Each worker times `steps` bare steps (after warm-up) three times and keeps the fastest
window, with a barrier around each window; per-stage seconds come from the pipeline's own
timers. Parallel efficiency E = T(1 rank) / (2 T(2 ranks)) for the same N (strong) and
T(1 rank, N) / T(2 ranks, 2N) (weak). Prints a table, writes <out>/scaling.json and
.png.
"""

import argparse
import json
import os
import platform
import subprocess
import sys
import time
import tomllib
from datetime import date
from pathlib import Path

from throughput import BLOCK  # (the same scene as the throughput bench)

OUT = Path(__file__).resolve().parents[1] / "out"
# (width, height) m at dx = 0.01 -> N = w * h * 1e4; steps per timed window
SIZES = {2_000: (0.2, 1.0, 400), 4_000: (0.4, 1.0, 400), 20_000: (1.0, 2.0, 400),
         50_000: (1.0, 5.0, 160), 100_000: (2.0, 5.0, 80), 400_000: (4.0, 10.0, 20)}
STRONG = (20_000, 100_000, 400_000)
WEAK = ((50_000, 1), (100_000, 2))
QUICK_STRONG, QUICK_WEAK = (2_000,), ((2_000, 1), (4_000, 2))


def timed_windows(sim, comm, steps: int, windows: int = 3) -> list[float]:
    """Wall seconds of `windows` windows of `steps` steps each, a barrier around each."""
    out = []
    for _ in range(windows):
        comm.Barrier()
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.advance_one()
        comm.Barrier()
        out.append(time.perf_counter() - t0)
    return out


def worker(n: int, quick: bool) -> None:
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.config.load import resolve, validate
    from psph.solver.simulation import Simulation

    comm = MPI.COMM_WORLD
    w, hgt, steps = SIZES[n]
    if quick:
        steps = max(steps // 8, 3)
    scene = resolve(validate(tomllib.loads(BLOCK.format(n=n, w=w, hgt=hgt))))
    sim = Simulation(scene, make_slabs(scene, comm))
    for _ in range(3):
        sim.advance_one()
    for stage in sim.stages:
        stage.seconds = 0.0
    windows = timed_windows(sim, comm, steps)
    stage_s = {s.name: s.seconds / (3 * steps) for s in sim.stages}
    stages = comm.gather(stage_s, root=0)
    owned = comm.gather(sim.store.n_owned, root=0)
    halo = comm.gather(sim.store.n_halo, root=0)
    if comm.Get_rank() == 0:
        print(json.dumps({"particles": sim.n_global, "ranks": comm.Get_size(), "steps": steps,
                          "seconds_per_step": min(windows) / steps,
                          "windows_s": windows, "owned": owned, "halo": halo,
                          "stage_seconds_per_step": stages}))


def drive(quick: bool) -> None:
    strong_sizes, weak_cases = (QUICK_STRONG, QUICK_WEAK) if quick else (STRONG, WEAK)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1",
               OMP_NUM_THREADS="1")
    cases = sorted({(n, r) for n in strong_sizes for r in (1, 2)} | set(weak_cases))
    runs = []
    for n, r in cases:
        cmd = ["mpirun", "-n", str(r), sys.executable, __file__, "--worker", str(n)]
        if quick:
            cmd.append("--quick")
        res = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
        runs.append(json.loads(res.stdout.strip().splitlines()[-1]))
        print(f"  measured N = {n:,} on {r} rank(s): "
              f"{runs[-1]['seconds_per_step'] * 1e3:.1f} ms/step", flush=True)
    t = {(x["particles"], x["ranks"]): x["seconds_per_step"] for x in runs}
    strong = [{"particles": n, "t1_ms": 1e3 * t[n, 1], "t2_ms": 1e3 * t[n, 2],
               "speedup": t[n, 1] / t[n, 2], "efficiency": t[n, 1] / (2 * t[n, 2]),
               "psteps_per_s_per_core_2": n / t[n, 2] / 2} for n in strong_sizes]
    (n1, _), (n2, _) = weak_cases
    weak = {"particles_per_rank": n1, "t1_ms": 1e3 * t[n1, 1], "t2_ms": 1e3 * t[n2, 2],
            "efficiency": t[n1, 1] / t[n2, 2]}
    report = {"date": str(date.today()), "machine": platform.node(),
              "cpus": os.cpu_count(), "python": sys.version.split()[0], "quick": quick,
              "strong": strong, "weak": weak, "runs": runs}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "scaling.json").write_text(json.dumps(report, indent=2) + "\n")
    table(report)
    plot(report)


def table(report: dict) -> None:
    print(f"\npsph scaling, coupled elastic TPI step, {report['date']}, "
          f"{report['cpus']} cores{' (quick)' if report['quick'] else ''}")
    print(f"{'N':>9s} {'1 rank ms/step':>15s} {'2 ranks ms/step':>16s} {'speed-up':>9s} "
          f"{'efficiency':>11s}")
    for s in report["strong"]:
        print(f"{s['particles']:9,d} {s['t1_ms']:15.2f} {s['t2_ms']:16.2f} "
              f"{s['speedup']:9.3f} {100 * s['efficiency']:10.1f}%")
    w = report["weak"]
    print(f"weak: {w['particles_per_rank']:,} per rank: 1 rank {w['t1_ms']:.2f} ms, 2 ranks "
          f"{w['t2_ms']:.2f} ms/step, efficiency {100 * w['efficiency']:.1f}%")
    print(f"wrote {OUT / 'scaling.json'}")


def plot(report: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = report["strong"]
    n = [x["particles"] for x in s]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    a1.plot(n, [x["t1_ms"] for x in s], "o-", label="1 rank")
    a1.plot(n, [x["t2_ms"] for x in s], "s-", label="2 ranks")
    a1.plot(n, [x["t1_ms"] / 2 for x in s], "k:", label="ideal 2 ranks")
    a1.set_xscale("log")
    a1.set_yscale("log")
    a1.set_xticks(n, [f"{x // 1000}k" for x in n])
    a1.minorticks_off()
    a1.set_xlabel("particles")
    a1.set_ylabel("ms / step")
    a1.legend()
    a1.set_title("strong scaling")
    a2.bar([f"{x // 1000}k" for x in n], [100 * x["efficiency"] for x in s], color="C0",
           label="strong")
    a2.bar(["weak\n50k/rank"], [100 * report["weak"]["efficiency"]], color="C2",
           label="weak")
    a2.axhline(85, ls="--", c="grey", label="bar: 85 %")
    a2.set_ylim(0, 110)
    a2.set_ylabel("2-rank parallel efficiency (%)")
    a2.legend(loc="lower right")
    fig.suptitle(f"psph 1 -> 2 ranks, {report['date']}, {report['cpus']}-core machine")
    fig.tight_layout()
    fig.savefig(OUT / "scaling.png", dpi=110)
    print(f"wrote {OUT / 'scaling.png'}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worker", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--quick", action="store_true",
                    help="2,000 and 4,000 particles, an eighth of the steps (a smoke check)")
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of scaling.json and .png (default bench/out)")
    a = ap.parse_args()
    OUT = a.out
    if a.worker:
        worker(a.worker, a.quick)
    elif a.plot_only:
        rep = json.loads((OUT / "scaling.json").read_text())
        table(rep)
        plot(rep)
    else:
        drive(a.quick)

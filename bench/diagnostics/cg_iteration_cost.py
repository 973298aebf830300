"""Where a CG iteration of the projection spends its time on several ranks (issue 36:
the default run under a minute): the default scene (`terzaghi`, the paper's column)
stepped to 0.05 s untimed, then to --until timed, with each part of the solve wrapped
in a timer: the linear system of the step, the operator (`apply`), the halo and ghost
refresh, the inner products (`dots`) and, inside them, the integer Allreduce.

    mpirun -n 2 .venv/bin/python bench/diagnostics/cg_iteration_cost.py   # ~20 s
    mpirun -n 2 .venv/bin/python bench/diagnostics/cg_iteration_cost.py --until 0.3
    git worktree add /tmp/base 52b1709 && ln -s $PWD/.venv /tmp/base/.venv
    mpirun -n 2 env PYTHONPATH=/tmp/base .venv/bin/python \
        bench/diagnostics/cg_iteration_cost.py --tag 52b1709     # the revision before

Prints a table (microseconds per CG iteration, rank 0), writes
bench/out/cg_iteration_cost-np<P>.json and .png (a bar per part).
"""

import argparse
import json
import platform
import time
from datetime import date
from pathlib import Path

from mpi4py import MPI

import psph.solver.pcg as pcg_module
import psph.solver.pressure_solve as solve_module
from psph.app.run import make_slabs
from psph.config.load import load_scene
from psph.solver.simulation import Simulation

OUT = Path(__file__).resolve().parents[1] / "out"
PARTS = ("project", "pcg", "system", "apply", "refresh", "dots", "allreduce")


def timed(name: str, f, seconds: dict):
    def wrapper(*args, **kwargs):
        t0 = time.perf_counter()
        result = f(*args, **kwargs)
        seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - t0
        return result
    return wrapper


def measure(until: float) -> dict:
    comm = MPI.COMM_WORLD
    scene = load_scene("terzaghi", [f"time.end={2 * until}"])
    sim = Simulation(scene, make_slabs(scene, comm))
    seconds: dict[str, float] = {}
    solve = sim.pressure_solve
    inner = pcg_module.pcg

    def pcg_timed(apply, diag, rhs, x, n, dots, refresh, tol, maxiter, work):
        return inner(timed("apply", apply, seconds), diag, rhs, x, n,
                     timed("dots", dots, seconds), timed("refresh", refresh, seconds), tol,
                     maxiter, work)

    solve_module.pcg = timed("pcg", pcg_timed, seconds)
    solve.project = timed("project", solve.project, seconds)
    solve._system = timed("system", solve._system, seconds)
    # the CG's one collective since the chunk rows (c03b0b5; named allreduce_sum_into from
    # c03b0b5 to f2d0b9a)
    for name in ("allreduce_sum", "allreduce_sum_into"):
        if hasattr(sim.slabs, name):
            setattr(sim.slabs, name, timed("allreduce", getattr(sim.slabs, name), seconds))
    while sim.t < 0.05:
        sim.advance_one()
    seconds.clear()
    it0, step0 = solve.stats["iterations_total"], sim.step
    t0 = time.perf_counter()
    while sim.t < until:
        sim.advance_one()
    wall = time.perf_counter() - t0
    its, steps = solve.stats["iterations_total"] - it0, sim.step - step0
    return {"ranks": comm.size, "until_s": until, "steps": steps, "iterations": its,
            "iterations_per_step": its / steps, "wall_us_per_step": 1e6 * wall / steps,
            "us_per_iteration": {k: 1e6 * seconds.get(k, 0.0) / its for k in PARTS}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--until", type=float, default=0.15, help="end of the timed window, s")
    ap.add_argument("--tag", default="", help="suffix of the output files (another revision)")
    args = ap.parse_args()
    row = measure(args.until)
    rows = MPI.COMM_WORLD.gather(row)
    if MPI.COMM_WORLD.rank:
        return
    r = rows[0]
    import psph
    print(f"psph from {Path(psph.__file__).parent}")
    print(f"{r['ranks']} ranks, {r['steps']} steps, {r['iterations_per_step']:.2f} CG "
          f"iterations a step, {r['wall_us_per_step']:.0f} us a step")
    print("| part | " + " | ".join(f"rank {i} us/iteration" for i in range(len(rows))) + " |")
    print("|---|" + "---|" * len(rows))
    for k in PARTS:
        print(f"| {k} | " + " | ".join(f"{x['us_per_iteration'][k]:.0f}" for x in rows) + " |")
    OUT.mkdir(exist_ok=True)
    stem = OUT / (f"cg_iteration_cost-np{r['ranks']}" + (f"-{args.tag}" if args.tag else ""))
    stem.with_suffix(".json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.node(), "ranks": rows},
        indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.2))
    ax.bar(PARTS, [r["us_per_iteration"][k] for k in PARTS])
    ax.set_ylabel("us per CG iteration (rank 0)")
    ax.set_title(f"projection CG on {r['ranks']} ranks, paper's column")
    fig.tight_layout()
    fig.savefig(stem.with_suffix(".png"), dpi=120)
    print(f"wrote {stem}.json, .png")


if __name__ == "__main__":
    main()

"""The projection's recycled initial guess (issue 36, psph/solver/recycling.py): CG
iterations a step, loop time and the error of the default run's column against the basis
size L = `pressure.recycle` (0: the extrapolated warm start alone), on the ranks it is
started on.

    mpirun -n 2 .venv/bin/python bench/diagnostics/recycled_guess.py          # ~1.5 min
    mpirun -n 2 .venv/bin/python bench/diagnostics/recycled_guess.py --full   # ~5 min

The window is the first 0.3 s (the loading, the drained switch and T_v up to 0.17, where
most iterations are); --full runs each L to T_v = 1. Prints a table, writes
bench/out/recycled_guess-np<P>[-full].json and .png.
"""

import argparse
import json
import platform
import tempfile
from datetime import date
from pathlib import Path

from mpi4py import MPI

from psph.app.run import run
from psph.config.load import load_scene

OUT = Path(__file__).resolve().parents[1] / "out"
SIZES = (0, 8, 16, 32, 64)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true", help="to T_v = 1 (default: 0.3 s)")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    work = comm.bcast(tempfile.mkdtemp(prefix="psph-recycle-") if comm.rank == 0 else None)
    window = [] if args.full else ["time.end=0.3"]
    rows = []
    for size in SIZES:
        s = run(load_scene("terzaghi", window + [f"pressure.recycle={size}"]),
                Path(work) / f"L{size}", comm=comm, quiet=True)
        err = s["errors"]["pressure"]
        rows.append({"L": size, "cg_iterations_per_step": s["pressure_solve"]["iterations_mean"],
                     "cg_iterations_max": s["pressure_solve"]["iterations_max"],
                     "loop_s": s["loop_s"], "steps": s["steps"],
                     "pressure_solve_us_per_step": 1e6 * s["stage_seconds"][
                         "pressure_solve[pcg,jacobi]+correction"]["max_s"] / s["steps"],
                     "max_p_error_over_q": max(e["max_abs_p_error_over_q"]
                                               for e in err.values())})
    if comm.rank != 0:
        return
    print(f"recycled guess, {comm.size} rank(s), {'to T_v = 1' if args.full else '0.3 s'}")
    print("| L | CG it/step | max | pressure solve us/step | loop s | max abs(p - p_a)/q |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['L']} | {r['cg_iterations_per_step']:.2f} | {r['cg_iterations_max']} | "
              f"{r['pressure_solve_us_per_step']:.0f} | {r['loop_s']:.1f} | "
              f"{r['max_p_error_over_q']:.5f} |")
    OUT.mkdir(exist_ok=True)
    stem = OUT / (f"recycled_guess-np{comm.size}" + ("-full" if args.full else ""))
    stem.with_suffix(".json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.node(), "ranks": comm.size,
         "full": args.full, "rows": rows}, indent=1))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.4))
    a1.plot([r["L"] for r in rows], [r["cg_iterations_per_step"] for r in rows], "o-")
    a1.set(xlabel="basis size L (pressure.recycle)", ylabel="CG iterations / step")
    a2.plot([r["L"] for r in rows], [r["pressure_solve_us_per_step"] for r in rows], "o-",
            label="pressure solve")
    a2.plot([r["L"] for r in rows], [1e6 * r["loop_s"] / r["steps"] for r in rows], "s-",
            label="whole step")
    a2.set(xlabel="basis size L", ylabel="us / step")
    a2.legend()
    fig.suptitle(f"recycled guess, the default column, {comm.size} rank(s), {date.today()}")
    fig.tight_layout()
    fig.savefig(stem.with_suffix(".png"), dpi=110)


if __name__ == "__main__":
    main()

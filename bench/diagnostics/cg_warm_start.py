"""The projection's CG against the order of its warm start (issue 36: the default run
under a minute). The solve starts from the last increments extrapolated,
dp ~ 2 dp^n - dp^(n-1) (order 1, `PressureSolve.project`); this swaps that guess for
dp^n (order 0) or the quadratic 3 dp^n - 3 dp^(n-1) + dp^(n-2) (order 2) on the default
scene (`terzaghi`, 1 rank: rows keep their place) and counts CG iterations a step.

    .venv/bin/python bench/diagnostics/cg_warm_start.py              # ~1.5 min
    .venv/bin/python bench/diagnostics/cg_warm_start.py --until 0.6

Prints a table, writes bench/out/cg_warm_start.json and .png (iterations a step against
time for each order).
"""

import argparse
import json
import platform
from datetime import date
from pathlib import Path

import numpy as np
from mpi4py import MPI

from psph.app.run import make_slabs
from psph.config.load import load_scene
from psph.solver.simulation import Simulation

OUT = Path(__file__).resolve().parents[1] / "out"
ORDERS = (0, 1, 2)


def iterations(order: int, until: float) -> tuple[np.ndarray, np.ndarray, float]:
    """CG iterations of every step to `until` with the warm start of `order`, the step
    times, and max |p| at the end (the solutions agree to the CG tolerance)."""
    scene = load_scene("terzaghi", [f"time.end={until}"])
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
    solve = sim.pressure_solve
    st = sim.store
    history: list[np.ndarray] = []
    project = solve.project

    def project_with_guess() -> None:
        # `project` guesses 2 dp^n - dp_prev: set dp_prev so that the guess is this order's
        n = st.n_owned
        history.insert(0, st.p[:n] - st.p_prev[:n])
        del history[3:]
        if order == 0:
            st.dp_prev[:n] = history[0]
        elif order == 2 and len(history) == 3:
            st.dp_prev[:n] = 2.0 * history[0] - (3.0 * history[0] - 3.0 * history[1]
                                                  + history[2])
        project()

    solve.project = project_with_guess
    its, times = [], []
    while sim.t < until - 1e-12:
        before = solve.stats["iterations_total"]
        sim.advance_one()
        its.append(solve.stats["iterations_total"] - before)
        times.append(sim.t)
    return np.array(its), np.array(times), float(np.abs(st.p[:st.n_owned]).max())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--until", type=float, default=0.3, help="end of the run, s")
    args = ap.parse_args()
    rows, curves = [], {}
    for order in ORDERS:
        its, times, p_max = iterations(order, args.until)
        rows.append({"order": order, "steps": len(its), "mean": float(its.mean()),
                     "mean_after_500": float(its[500:].mean()), "max": int(its.max()),
                     "p_max_Pa": p_max})
        curves[order] = (times, its)
    print(f"default scene to t = {args.until} s on 1 rank: CG iterations a step")
    print("| warm start | steps | mean | mean after step 500 | max | max abs p (Pa) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(f"| order {r['order']} | {r['steps']} | {r['mean']:.2f} | "
              f"{r['mean_after_500']:.2f} | {r['max']} | {r['p_max_Pa']:.2f} |")
    OUT.mkdir(exist_ok=True)
    (OUT / "cg_warm_start.json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.node(), "until_s": args.until,
         "rows": rows}, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 3.2))
    for order, (times, its) in curves.items():
        k = max(1, len(its) // 400)  # a mean over k steps per point
        m = len(its) // k * k
        ax.plot(times[:m].reshape(-1, k).mean(1), its[:m].reshape(-1, k).mean(1),
                label=f"order {order}")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("CG iterations a step")
    ax.set_title("projection CG against its warm start, paper's column")
    ax.legend()
    fig.tight_layout()
    fig.savefig(OUT / "cg_warm_start.png", dpi=120)
    print(f"wrote {OUT / 'cg_warm_start.json'}, .png")


if __name__ == "__main__":
    main()

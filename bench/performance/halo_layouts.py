"""Slabs against boxes along two axes on 4 ranks: the halo each rank holds and
the step's time, measured on the 3D coupled elastic block of `throughput.py` (30 x 30 x
60 particles, 54,000; TPI), cut in 4 slabs along z (its longest side) and in 2 x 2
boxes (z, then x).

    .venv/bin/python bench/performance/halo_layouts.py            # ~3 min (4 ranks on 2 cores)
    .venv/bin/python bench/performance/halo_layouts.py --quick    # a 10 x 10 x 20 block, 1 step

Each layout runs under `mpirun -n 4` (oversubscribed here: the step times compare the
layouts on this machine, not a cluster's); 2 warm-up steps, then 5 timed. Prints a table,
writes <out>/halo_layouts.json and .png (halo rows per rank, both layouts).
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

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "bench" / "out"
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none", "NUMBA_NUM_THREADS": "1"}
RANKS, WARM, STEPS = 4, 2, 5


def worker(cuts: str, quick: bool = False) -> None:
    """One layout under mpirun: rank 0 prints a JSON line of the per-rank counts."""
    import throughput
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.config.load import resolve, validate
    from psph.solver.simulation import Simulation

    comm = MPI.COMM_WORLD
    w, hgt = (0.1, 0.2) if quick else (0.3, 0.6)
    text = throughput.BLOCK_3D.format(n=round(w * w * hgt * 1e6), w=w, hgt=hgt, hf=1.3) + \
        f'\n[decomposition]\ncuts = "{cuts}"\nrebalance_every = 0\n'
    scene = resolve(validate(tomllib.loads(text)))
    sim = Simulation(scene, make_slabs(scene, comm))
    warm, steps = (0, 1) if quick else (WARM, STEPS)
    for _ in range(warm):
        sim.advance_one()
    comm.Barrier()
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.advance_one()
    comm.Barrier()
    step = (time.perf_counter() - t0) / steps
    halo = comm.gather(int(sim.store.n_halo))
    owned = comm.gather(int(sim.store.n_owned))
    if comm.Get_rank() == 0:
        print(json.dumps({"cuts": cuts, "layout": sim.slabs.describe(), "halo": halo,
                          "owned": owned, "step_s": step}))


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.8))
    for k, r in enumerate(rows):
        ranks = [i + 0.2 * (k - 0.5) for i in range(len(r["halo"]))]
        ax.bar(ranks, r["halo"], width=0.4, label=f"{r['cuts']} (step {r['step_s']:.2f} s)")
    ax.set(xlabel="rank", ylabel="halo rows",
           title="4 ranks, the 3D block of 54,000 particles: halo a rank")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worker", choices=("slabs", "boxes"), help=argparse.SUPPRESS)
    ap.add_argument("--quick", action="store_true",
                    help="a 10 x 10 x 20 particle block, one step (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON and PNG (default bench/out)")
    args = ap.parse_args()
    if args.worker:
        worker(args.worker, args.quick)
        return
    rows = []
    for cuts in ("slabs", "boxes"):
        cmd = ["mpirun", "-n", str(RANKS), sys.executable, __file__, "--worker", cuts]
        cmd += ["--quick"] if args.quick else []
        r = subprocess.run(cmd, cwd=ROOT, env={**os.environ, **MPI_ENV}, capture_output=True,
                           text=True)
        if r.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr[-2000:]}")
        rows.append(json.loads(r.stdout.strip().splitlines()[-1]))
    print(f"{'layout':>8s} {'owned a rank':>22s} {'halo a rank':>24s} {'max halo/owned':>15s} "
          f"{'step (s)':>9s}")
    for r in rows:
        ratio = max(h / o for h, o in zip(r["halo"], r["owned"], strict=True))
        r["max_halo_per_owned"] = ratio
        print(f"{r['cuts']:>8s} {str(r['owned']):>22s} {str(r['halo']):>24s} {ratio:15.3f} "
              f"{r['step_s']:9.3f}")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "halo_layouts.json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.platform(), "ranks": RANKS,
         "rows": rows}, indent=1) + "\n")
    plot(rows, args.out / "halo_layouts.png")
    print(f"wrote {args.out / 'halo_layouts.json'} and .png")


if __name__ == "__main__":
    main()

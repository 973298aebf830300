"""Where a step of the throughput bench's 3D coupled block goes (issue 37,
docs/performance.md): `Simulation`'s per-stage timers over a few steps of the block of
`bench/performance/throughput.py` (30 x 30 x 60 particles, four slip walls, a fixed base,
a drained top plane), each rank's column, and the drained plane's image pass
(`images.image_sums`, part of the sweep's stage) timed on its own.

    mpirun -n 1 .venv/bin/python bench/diagnostics/stage_times_3d.py [--h-factor 1.2] [--steps 10]
    mpirun -n 2 .venv/bin/python bench/diagnostics/stage_times_3d.py
"""

import argparse
import sys
import time
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "performance"))


def main() -> None:
    import throughput
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.config.load import resolve, validate
    from psph.solver.simulation import Simulation

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--h-factor", type=float, default=1.2)
    ap.add_argument("--steps", type=int, default=10)
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    text = throughput.BLOCK_3D.format(n=54000, w=0.3, hgt=0.6, hf=args.h_factor)
    scene = resolve(validate(tomllib.loads(text)))
    sim = Simulation(scene, make_slabs(scene, comm))
    image_sums = sim.kernels.image_sums
    image_seconds = [0.0]

    def timed_image_sums(*a):
        t0 = time.perf_counter()
        image_sums(*a)
        image_seconds[0] += time.perf_counter() - t0

    sim.kernels = sim.kernels._replace(image_sums=timed_image_sums)
    for _ in range(2):  # compiled, halo and ghosts set up
        sim.advance_one()
    for stage in sim.stages:
        stage.seconds = 0.0
    image_seconds[0] = 0.0
    comm.Barrier()
    t0 = time.perf_counter()
    for _ in range(args.steps):
        sim.advance_one()
    comm.Barrier()
    wall = time.perf_counter() - t0
    ms = 1e3 / args.steps
    rows = comm.gather([(s.name, s.seconds * ms) for s in sim.stages]
                       + [("  of which the drained plane's images", image_seconds[0] * ms)],
                       root=0)
    counts = comm.gather((sim.store.n_owned, sim.store.n_halo, sim.store.n_ghost), root=0)
    if comm.Get_rank() == 0:
        ranks = comm.Get_size()
        print(f"{sim.n_global} particles, h = {args.h_factor} dx, {ranks} rank(s): "
              f"{wall * ms:.1f} ms a step, "
              f"{sim.n_global * args.steps / wall / ranks:,.0f} particle-steps/s/core")
        print("owned / halo / ghost rows per rank:", counts)
        print(f"{'stage, ms a step':42s}" + "".join(f"{'rank ' + str(r):>9s}"
                                                    for r in range(ranks)))
        for i, (name, _) in enumerate(rows[0]):
            print(f"{name:42s}" + "".join(f"{rows[r][i][1]:9.2f}" for r in range(ranks)))


if __name__ == "__main__":
    main()

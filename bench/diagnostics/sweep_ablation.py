"""Where the 3D pair sweep's time goes (issue 37, docs/performance.md): the sweep of one
step of the bench's 3D coupled elastic block (`bench/performance/throughput.py`, 16,000
particles, 699,708 pairs, one rank), best of 10, and the whole step.

    python bench/diagnostics/sweep_ablation.py              # the code as it is
    python bench/diagnostics/sweep_ablation.py --cell-order # the store's rows permuted
                                                            # into cell order first

The ablations remove parts of `interactions.make_pair_sums` in 3D (2D untouched) in a
worktree: `git worktree add /tmp/x HEAD && git -C /tmp/x apply $PWD/bench/diagnostics/
sweep_ablation_<name>.patch`, then this script with `PYTHONPATH=/tmp/x`:
`no_a_side` (a's sums not accumulated), `no_sums` (no sums, the pair's arithmetic kept
alive by one sum), `candidates_only` (the candidate loop and the distance test). Their
results are wrong by construction; only the time counts. `sweep_a_side_registers.patch`
(applied the same way) is a variant with the same sums: a's shares of its forward pairs
held in tuples and written once after them. Compare in the same minute (this
VM drifts): pause other runs (kill -STOP) while measuring.
The tables of 2026-12-05 in docs/performance.md were measured on the sweep's cells of
side 2h: a worktree of 28bc41c, the last commit before the 3D pair grid of side h
(`neighbours.pair_cell_span`), reproduces them, and `sweep_a_side_registers.patch`
applies only there.
"""

import sys
import time
import tomllib
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "performance"))


def main() -> None:
    import throughput
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.config.load import resolve, validate
    from psph.solver.simulation import Simulation

    text = throughput.BLOCK_3D.format(n=16000, w=0.2, hgt=0.4, hf=1.3)
    scene = resolve(validate(tomllib.loads(text)))
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_WORLD))
    for _ in range(3):
        sim.advance_one()
    st = sim.store
    n = st.n_owned
    if "--cell-order" in sys.argv:  # rows of one cell next to each other (same sums)
        c = np.floor((st.x[:n] - st.x[:n].min(axis=0)) / (2 * scene.h)).astype(np.int64)
        cell = (c[:, 2] * (c[:, 1].max() + 1) + c[:, 1]) * (c[:, 0].max() + 1) + c[:, 0]
        perm = np.lexsort((st.key[:n], cell))
        for a in st.arrays.values():
            a[:n] = a[:n][perm]
        sim.advance_one()  # ghosts and cell lists of the new rows
    best = min(_timed(sim._interactions) for _ in range(10))
    step = sum(_timed(sim.advance_one) for _ in range(5)) / 5
    print(f"{n} particles, {sim.n_pairs} pairs: sweep {best * 1e3:.1f} ms "
          f"({best / sim.n_pairs * 1e9:.0f} ns a pair), step {step * 1e3:.1f} ms, "
          f"{n / step / 1e6:.3f} M particle-steps/s")


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()

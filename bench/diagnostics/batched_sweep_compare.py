"""A batched 3D pair sweep against the scalar one (issue 37, docs/performance.md): apply
`batched_sweep_attempt.patch` (it adds psph/kernels/interactions_batched.py) to a worktree
of 28bc41c, the last commit whose 3D sweep ran on cells of side 2h, as the patch's kernel
does (`git worktree add /tmp/x 28bc41c && git -C /tmp/x apply $PWD/bench/diagnostics/
batched_sweep_attempt.patch`), then

    NUMBA_CACHE_DIR=/tmp/nbc PYTHONPATH=/tmp/x python bench/diagnostics/batched_sweep_compare.py

captures one sweep of the bench's 3D coupled elastic block, runs both kernels on it and
prints their largest difference (relative to each column's largest value), whether the
recorded pairs are the same, the best of 10 times of each, and the most frequent vector
instructions of the batch's machine code: scalar (`sd`) or SIMD (`pd`, zmm). A fresh
NUMBA_CACHE_DIR, as numba cannot show the code of a cached kernel.
"""

import collections
import re
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "performance"))


def _best(fn, args, reps=10) -> float:
    best = 1e9
    for _ in range(reps):
        t0 = time.perf_counter()
        fn(*args)
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    import throughput
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.config.load import resolve, validate
    from psph.kernels import interactions_batched
    from psph.kernels.bundles import PairRecord
    from psph.kernels.interactions import pair_sums_3d
    from psph.solver.simulation import Simulation

    scene = resolve(validate(tomllib.loads(throughput.BLOCK_3D.format(n=16000, w=0.2, hf=1.3,
                                                                       hgt=0.4))))
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_WORLD))
    for _ in range(3):
        sim.advance_one()
    captured = {}
    scalar = sim.kernels.pair_sums

    def capture(*args):
        captured["args"] = args
        return scalar(*args)

    sim.kernels = sim.kernels._replace(pair_sums=capture)
    sim._interactions()
    n_total, n_owned, n_real, f, cells, par, sums, rec = captured["args"]
    n_slots = int(cells.cell_start[int(np.prod(cells.ncell))])
    packed = np.zeros((n_slots, interactions_batched.NPACK))
    interactions_batched.pack_pair_fields(cells.order, n_slots, f.x, f.v, f.v_slip, f.stress,
                                          f.p, f.p_prev, f.poro, f.vol, f.rho, f.perm, f.acc,
                                          packed)
    out = {}
    for name, fn, cl in (("scalar", pair_sums_3d, cells),
                         ("batched", interactions_batched.pair_sums_batched,
                          cells._replace(x_sorted=packed))):
        s = np.zeros_like(sums)
        r = PairRecord(np.zeros_like(rec.pairs), np.zeros_like(rec.pair_g))
        args = (n_total, n_owned, n_real, f, cl, par, s, r)
        n = fn(*args)
        out[name] = (n, s[:n_owned].copy(), r, _best(fn, args))
    (n1, s1, r1, t1), (n2, s2, r2, t2) = out["scalar"], out["batched"]
    scale = np.abs(s1).max(axis=0) + 1e-300
    m = min(n1, r1.pairs.shape[0])
    print(f"pairs {n1} and {n2}, the same: {np.array_equal(r1.pairs[:m], r2.pairs[:m])}; "
          f"largest difference {(np.abs(s1 - s2).max(axis=0) / scale).max():.2e} of a "
          f"column's largest value; scalar {t1 * 1e3:.1f} ms, batched {t2 * 1e3:.1f} ms")
    for asm in interactions_batched._batch.inspect_asm().values():
        count = collections.Counter()
        for line in asm.splitlines():
            hit = re.match(r"\s+(v\w+)\s+(.*)", line)
            if hit:
                reg = "zmm" if "zmm" in hit.group(2) else "ymm" if "ymm" in hit.group(2) else ""
                count[f"{hit.group(1)} {reg}".strip()] += 1
        print("batch loop:", ", ".join(f"{k} {v}" for k, v in count.most_common(8)))


if __name__ == "__main__":
    main()

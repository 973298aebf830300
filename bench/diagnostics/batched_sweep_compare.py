"""A batched 3D pair sweep against the scalar one (issue 37, docs/performance.md): apply
`batched_sweep_attempt.patch` (it adds psph/kernels/interactions_batched.py) to a worktree
(`git worktree add /tmp/x HEAD && git -C /tmp/x apply $PWD/bench/diagnostics/
batched_sweep_attempt.patch`), then

    PYTHONPATH=/tmp/x python bench/diagnostics/batched_sweep_compare.py elastic

captures one sweep of the bench's 3D coupled elastic block, runs both kernels on it and
prints their largest difference (relative to each column's largest value), whether the
recorded pairs are the same, the best of 10 times of each, and the SIMD instructions in the
batch's machine code (numba's cache off for it: NUMBA_CACHE_DIR=/tmp/somewhere).
"""
import sys, time, tomllib
import numpy as np
sys.path.insert(0, "bench/performance")
from mpi4py import MPI
from psph.app.run import make_slabs
from psph.config.load import resolve, validate, load_scene
from psph.solver.simulation import Simulation
from psph.kernels.interactions import pair_sums_3d
from psph.kernels.interactions_batched import pair_sums_batched
from psph.kernels.bundles import PairFields, Cells, PairParams, PairRecord
import throughput as tp

def setup(which):
    if which == "elastic":
        scene = resolve(validate(tomllib.loads(tp.BLOCK_3D.format(n=16000, w=0.2, hgt=0.4))))
    else:
        scene = resolve(validate(tomllib.loads(tp.COLLAPSE_3D.format(n=27000, w=0.6, far=1.8))))
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_WORLD))
    for _ in range(3):
        sim.advance_one()
    return sim

for which in sys.argv[1:]:
    sim = setup(which)
    k = sim.kernels
    captured = {}
    orig = k.pair_sums
    def capture(*args):
        captured["args"] = args
        return orig(*args)
    sim.kernels = k._replace(pair_sums=capture)
    try:
        sim._interactions()
    except Exception as e:
        print("capture failed", e)
    args = captured.get("args")
    if args is None:
        print("no capture"); continue
    n_total, n_owned, n_real, f, cells, par, sums, rec = args
    s1 = np.zeros_like(sums); s2 = np.zeros_like(sums)
    rec1 = PairRecord(np.zeros_like(rec.pairs), np.zeros_like(rec.pair_g))
    rec2 = PairRecord(np.zeros_like(rec.pairs), np.zeros_like(rec.pair_g))
    n1 = pair_sums_3d(n_total, n_owned, n_real, f, cells, par, s1, rec1)
    n2 = pair_sums_batched(n_total, n_owned, n_real, f, cells, par, s2, rec2)
    a, b = s1[:n_owned], s2[:n_owned]
    scale = np.abs(a).max(axis=0) + 1e-300
    print(which, "pairs", n1, n2, "record", par.record, "as_n", par.as_n, "coupled", par.coupled,
          "max rel diff per column", (np.abs(a - b).max(axis=0) / scale).max())
    if par.record:
        m = min(n1, rec.pairs.shape[0])
        print("  pairs equal", np.array_equal(rec1.pairs[:m], rec2.pairs[:m]), "g diff", np.abs(rec1.pair_g[:m] - rec2.pair_g[:m]).max())
    for name, fn, ss in (("scalar", pair_sums_3d, s1), ("batched", pair_sums_batched, s2)):
        best = 1e9
        for _ in range(10):
            t0 = time.perf_counter(); fn(n_total, n_owned, n_real, f, cells, par, ss, rec1); best = min(best, time.perf_counter() - t0)
        print(f"  {name}: {best*1e3:.1f} ms")
if True:  # the batch loop's instructions: scalar (sd) or SIMD (pd, zmm)
    import re, collections
    from psph.kernels import interactions_batched as ib
    for fn in (ib._batch,):
        for sig, asm in fn.inspect_asm().items():
            c = collections.Counter()
            for l in asm.splitlines():
                m = re.match(r"\s+(v\w+)\s+(.*)", l)
                if m:
                    c[(m.group(1), "zmm" if "zmm" in m.group(2) else "ymm" if "ymm" in m.group(2) else "x")] += 1
            print(fn.__name__, len(asm.splitlines()), [kv for kv in c.most_common(14)])

"""How to write a kernel once for 2D and 3D without slowing 2D (issue 37): the velocity
sweep (`interactions.velocity_gradient_sums`) over the pairs of a jittered 2D lattice, as

  * hand-written: the 2D sweep of revision 7d83a70 (read from git, not copied here);
  * factory: the code's `make_velocity_gradient_sums(2)`: dim and columns constants of
    the compiled function, a pair's components loaded into scalars first (`dims.py`);
  * factory, loads in the loops: the same, reading v and pair_g inside the loops over
    components, after stores into `sums`;
  * run-time dim: the loops over `dim = v.shape[1]` with the columns as arguments;

and the 3D factory's sweep on a 3D lattice, per pair. Each variant's 2D sums are checked
bit for bit against the hand-written sweep.

    .venv/bin/python bench/diagnostics/generic_dim_kernel.py      # ~1 min (compiles)

Prints a table, writes bench/out/generic_dim_kernel.json and .png.
"""

import importlib.util
import json
import platform
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import numba as nb
import numpy as np

from psph.kernels.interactions import velocity_gradient_sums, velocity_gradient_sums_3d
from psph.kernels.neighbours import cell_lists, neighbour_pairs
from psph.kernels.spline import dw_cubic_dim
from psph.kernels.sum_columns import GN_XX, GS_XX, GV_XX, NSUMS, sum_layout

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "bench" / "out"
HAND_WRITTEN = "7d83a70"  # the last revision with the hand-written 2D sweep


def hand_written():
    """psph/kernels/interactions.py of revision HAND_WRITTEN, loaded from git."""
    source = subprocess.run(["git", "-C", str(ROOT), "show",
                             f"{HAND_WRITTEN}:psph/kernels/interactions.py"], check=True,
                            capture_output=True, text=True).stdout
    path = Path(tempfile.mkdtemp(prefix="psph-sweep-")) / "interactions_2d.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("interactions_2d", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@nb.njit(error_model="numpy")
def sweep_runtime_dim(n_owned, n_real, n_pairs, pairs, pair_g, v, v_slip, poro, vol, coupled,
                      sums, gv, gs, gn):
    dim = v.shape[1]
    for i in range(n_owned):
        for c in range(dim * dim):
            sums[i, gv + c] = 0.0
            sums[i, gs + c] = 0.0
            if coupled:
                sums[i, gn + c] = 0.0
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        ghost_pair = a >= n_real or b >= n_real
        for side in range(2):
            i = a if side == 0 else b
            j = b if side == 0 else a
            if i >= n_owned:
                continue
            vj = vol[j]
            wn = vj * (1.0 - poro[j])
            for m in range(dim):
                dvm = v[b, m] - v[a, m]
                dsm = v_slip[b, m] - v_slip[a, m] if ghost_pair else dvm
                for q in range(dim):
                    sums[i, gv + m * dim + q] += vj * dvm * pair_g[k, q]
                    if ghost_pair:
                        sums[i, gs + m * dim + q] += vj * (dsm - dvm) * pair_g[k, q]
                    if coupled:
                        sums[i, gn + m * dim + q] += wn * dsm * pair_g[k, q]


def make_sweep_loads_in_loops(dim: int):
    gv, gs, gn = GV_XX, GS_XX, GN_XX

    @nb.njit(error_model="numpy")
    def sweep(n_owned, n_real, n_pairs, pairs, pair_g, v, v_slip, poro, vol, coupled, sums):
        for i in range(n_owned):
            for c in range(dim * dim):
                sums[i, gv + c] = 0.0
                sums[i, gs + c] = 0.0
                if coupled:
                    sums[i, gn + c] = 0.0
        for k in range(n_pairs):
            a = pairs[k, 0]
            b = pairs[k, 1]
            ghost_pair = a >= n_real or b >= n_real
            for side in range(2):
                i = a if side == 0 else b
                j = b if side == 0 else a
                if i >= n_owned:
                    continue
                vj = vol[j]
                for m in range(dim):
                    dvm = v[b, m] - v[a, m]
                    for q in range(dim):
                        sums[i, gv + m * dim + q] += vj * dvm * pair_g[k, q]
                if ghost_pair:
                    for m in range(dim):
                        ddm = (v_slip[b, m] - v_slip[a, m]) - (v[b, m] - v[a, m])
                        for q in range(dim):
                            sums[i, gs + m * dim + q] += vj * ddm * pair_g[k, q]
                if coupled:
                    wn = vj * (1.0 - poro[j])
                    for m in range(dim):
                        dsm = v_slip[b, m] - v_slip[a, m] if ghost_pair else v[b, m] - v[a, m]
                        for q in range(dim):
                            sums[i, gn + m * dim + q] += wn * dsm * pair_g[k, q]
    return sweep


def cloud(dim: int, side: int, seed: int = 0):
    """A jittered lattice of side^dim particles (dx = 0.01 m, h = 1.2 dx), its pairs and
    their kernel gradients, and random fields; the last 2 % of rows stand for ghosts."""
    rng = np.random.default_rng(seed)
    dx, h = 0.01, 0.012
    g = (np.arange(side) + 0.5) * dx
    x = np.array(np.meshgrid(*[g] * dim, indexing="ij")).reshape(dim, -1).T
    x += rng.uniform(-0.2, 0.2, x.shape) * dx
    n = len(x)
    cell_start, order, ncell = cell_lists(x, h)
    pairs = np.zeros((60 * n, 2), np.int64)
    m = neighbour_pairs(n, x, h, cell_start, order, ncell, pairs)
    pairs = pairs[:m]
    d = x[pairs[:, 1]] - x[pairs[:, 0]]
    r = np.linalg.norm(d, axis=1)
    pair_g = -np.array([dw_cubic_dim(ri, h, dim) for ri in r])[:, None] * d / r[:, None]
    v = rng.normal(size=(n, dim))
    v_slip = v + 0.1 * rng.normal(size=(n, dim))
    n_real = n - n // 50
    args = (n_real - n // 100, n_real, m, pairs, pair_g, v, v_slip,
            rng.uniform(0.3, 0.5, n), rng.uniform(0.9, 1.1, n) * dx ** dim, True)
    return args, n, m


def fused_sweeps(hand_pair_sums) -> list[dict]:
    """The fused pair sweep (`pair_sums`, cell lists and all the sums of a coupled step)
    hand-written (HAND_WRITTEN) and from the factory, interleaved, on a 2D cloud."""
    from psph.kernels.bundles import PairFields, PairParams, PairRecord, sorted_cells
    from psph.kernels.interactions import pair_sums

    rng = np.random.default_rng(1)
    dx, h, side = 0.01, 0.012, 141
    g = (np.arange(side) + 0.5) * dx
    x = np.array(np.meshgrid(g, g, indexing="ij")).reshape(2, -1).T
    x += rng.uniform(-0.2, 0.2, x.shape) * dx
    n = len(x)
    fields = PairFields(x, rng.normal(size=(n, 2)), rng.normal(size=(n, 2)),
                        rng.normal(size=(n, 4)), rng.normal(size=n), rng.normal(size=n),
                        rng.uniform(0.3, 0.5, n), np.full(n, dx * dx),
                        rng.uniform(1.8e3, 2e3, n), rng.uniform(1e-4, 2e-4, n),
                        rng.normal(size=(n, 2)), np.zeros((n, 3)))
    cells = sorted_cells(*cell_lists(x, h), x)
    par = PairParams(h, 0.5, 1.0, 0.0, 20.0, 0.0, -9810.0, True, False, 0.0, 1.0, 1.0,
                     True).typed()
    rec = PairRecord(np.zeros((30 * n, 2), np.int64), np.zeros((30 * n, 2)))
    sums = {"hand": np.zeros((n, NSUMS)), "factory": np.zeros((n, NSUMS))}
    funcs = {"hand": hand_pair_sums, "factory": pair_sums}
    best: dict[str, float] = {}
    for _ in range(15):  # interleaved: a change of machine load hits both alike
        for name, f in funcs.items():
            best[name] = min(best.get(name, np.inf), best_ms(
                f, (n, n - 100, n - 300, fields, cells, par, sums[name], rec), repeats=1,
                calls=5))
    m = pair_sums(n, n - 100, n - 300, fields, cells, par, sums["factory"], rec)
    same = bool(np.array_equal(sums["hand"], sums["factory"]))
    return [{"variant": f"fused pair sweep, {label}", "dim": 2, "pairs": m, "ms": best[k],
             "ns_per_pair": 1e6 * best[k] / m, "bitwise_2d": same}
            for k, label in (("hand", f"hand-written ({HAND_WRITTEN})"),
                             ("factory", "factory (the code's)"))]


def best_ms(f, args, extra=(), repeats=7, calls=20) -> float:
    f(*args, *extra)
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(calls):
            f(*args, *extra)
        best = min(best, (time.perf_counter() - t) / calls)
    return 1e3 * best


def main() -> None:
    args2, n2, m2 = cloud(2, 141)
    reference = np.zeros((n2, NSUMS))
    old = hand_written()
    hand = old.velocity_gradient_sums
    rows = []
    variants = (("hand-written 2D (7d83a70)", hand, ()),
                ("factory (the code's)", velocity_gradient_sums, ()),
                ("factory, loads in the loops", make_sweep_loads_in_loops(2), ()),
                ("run-time dim", sweep_runtime_dim, (GV_XX, GS_XX, GN_XX)))
    hand(*args2, reference)
    for name, f, extra in variants:
        sums = np.zeros((n2, NSUMS))
        ms = best_ms(f, args2 + (sums,), extra)
        rows.append({"variant": name, "dim": 2, "pairs": m2, "ms": ms,
                     "ns_per_pair": 1e6 * ms / m2,
                     "bitwise_2d": bool(np.array_equal(sums, reference))})
    rows += fused_sweeps(old.pair_sums)
    args3, n3, m3 = cloud(3, 27)
    ms = best_ms(velocity_gradient_sums_3d, args3 + (np.zeros((n3, sum_layout(3).NSUMS)),))
    rows.append({"variant": "factory (the code's), 3D", "dim": 3, "pairs": m3, "ms": ms,
                 "ns_per_pair": 1e6 * ms / m3, "bitwise_2d": None})
    print("| variant | dim | pairs | ms a sweep | ns a pair | 2D bits as hand-written |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        bits = "–" if r["bitwise_2d"] is None else ("yes" if r["bitwise_2d"] else "no")
        print(f"| {r['variant']} | {r['dim']} | {r['pairs']:,} | {r['ms']:.3f} | "
              f"{r['ns_per_pair']:.2f} | {bits} |")
    OUT.mkdir(exist_ok=True)
    (OUT / "generic_dim_kernel.json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.node(), "rows": rows},
        indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 2.8))
    ax.barh([r["variant"] for r in rows], [r["ns_per_pair"] for r in rows])
    ax.set_xlabel("ns per pair (velocity sweep)")
    ax.invert_yaxis()
    fig.tight_layout()
    fig.savefig(OUT / "generic_dim_kernel.png", dpi=120)
    print(f"wrote {OUT / 'generic_dim_kernel.json'}, .png")
    sys.stdout.flush()


if __name__ == "__main__":
    main()

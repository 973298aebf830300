"""A model of strong and weak scaling to 1,024 ranks in 2D slabs, from costs measured here.

Measured on this machine (`mpirun` workers of this script, the throughput bench's coupled
elastic TPI block at dx = 0.01, h = 1.3 dx, slabs along its long side):

- compute: seconds per owned particle-step on one rank (c), and what a 2-rank step takes
  beyond its owned particles and its messages, fitted over the three sizes as particle-
  steps slower by a share s where ranks share a node's memory plus a cost per halo row
  (c_h);
- traffic per step, counted on 2 ranks by wrapping the communicator: point-to-point
  messages and bytes per slab face, collectives per step;
- the network: ping-pong latency and bandwidth between two ranks, and the latency of an
  8-byte allreduce.

The model of one step on P ranks (one core each), N particles, a slab face of F particles
(the section's height over dx) and a halo of `rows` lattice rows per face:

    T(P) = c (1 + s) (N / P) + c_h (2 F rows) + 2 (m alpha + b F rows / beta)
           + k ceil(log2 P) alpha_c

with m messages per face and step, b bytes per halo particle (two faces, one on 2 ranks)
and k collectives. It is checked
against the measured 1-, 2- and 4-rank times (4 ranks share the 2 cores here: the compute
part is counted twice). The section for the table: an aspect ratio L / H = 10 (a hillslope
cross-section), slabs along L, so F = sqrt(N / 10); the slab width L / P may not fall below
the halo width 2h (`slab_cuts`), which caps P. Cluster network: the measured latencies and
bandwidth of this machine (shared memory) and, as stated assumptions, an InfiniBand-class
interconnect (alpha = 2 us, beta = 10 GB/s, alpha_c = 3 us per tree level).

    python bench/performance/scaling_model.py            # measures (about 75 s), then models
    python bench/performance/scaling_model.py --model-only   # from <out>/scaling_model.json
    python bench/performance/scaling_model.py --quick        # 2,000 and 4,000 particles

Prints the tables, writes <out>/scaling_model.json and .png (`--out`, default bench/out).
"""

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time
import tomllib
from datetime import date
from pathlib import Path

from scaling import timed_windows
from throughput import BLOCK

OUT = Path(__file__).resolve().parents[1] / "out"
N_CHECK = (20_000, 100_000, 400_000)
SIZES = {20_000: (1.0, 2.0, 200), 100_000: (2.0, 5.0, 40), 400_000: (4.0, 10.0, 10),
         2_000: (0.2, 1.0, 20), 4_000: (0.4, 1.0, 10)}
N_QUICK = (2_000, 4_000)
ASPECT = 10.0  # L / H of the modelled section
HALO_ROWS = 3  # ceil(2 h / dx) at h = 1.3 dx
HALO_SHARE = 0.5  # assumed least cost of a halo row, in owned particle-steps
CLUSTER = {"alpha_s": 2e-6, "beta_Bps": 10e9, "alpha_coll_s": 3e-6}
P_TABLE = (1, 2, 4, 16, 64, 256, 1024)


class CountingComm:
    """Forwards to an mpi4py communicator and counts messages, bytes and collectives."""

    P2P = ("Isend", "Send", "Sendrecv")
    COLLECTIVE = ("allreduce", "Allreduce", "allgather", "Allgather", "Alltoall",
                  "Alltoallv", "bcast", "Bcast", "gather", "Barrier")

    def __init__(self, comm):
        self._comm = comm
        self.messages = 0
        self.bytes = 0
        self.collectives = 0

    def __getattr__(self, name):
        attr = getattr(self._comm, name)
        if name in self.P2P:
            def p2p(buf, *args, **kw):
                self.messages += 1
                self.bytes += memoryview(buf[0] if isinstance(buf, list) else buf).nbytes
                return attr(buf, *args, **kw)
            return p2p
        if name in self.COLLECTIVE:
            def coll(*args, **kw):
                self.collectives += 1
                return attr(*args, **kw)
            return coll
        return attr


def measure_step(text: str, steps: int, warm: int = 3) -> None:
    """One measurement under mpirun of the scene `text` (TOML): step time, owned and halo
    rows, traffic per step (counted on the communicator), the slab face in particles;
    rank 0 prints it as JSON."""
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.config.load import resolve, validate
    from psph.solver.simulation import Simulation

    comm = MPI.COMM_WORLD
    data = tomllib.loads(text)
    data.setdefault("decomposition", {})["cuts"] = "slabs"  # the model's slabs, measured
    scene = resolve(validate(data))
    sim = Simulation(scene, make_slabs(scene, comm))
    for _ in range(warm):
        sim.advance_one()
    counting = CountingComm(sim.slabs.comm)
    sim.slabs.comm = counting
    windows = timed_windows(sim, comm, steps)
    per = 3 * steps
    lo, hi = scene.domain.min, scene.domain.max
    across = [d for d in range(scene.dim) if d != sim.slabs.axis]
    face = math.prod((hi[d] - lo[d]) / scene.particles.dx for d in across)
    rec = {"particles": sim.n_global, "ranks": comm.Get_size(), "axis": sim.slabs.axis,
           "seconds_per_step": min(windows) / steps,
           "owned": comm.gather(sim.store.n_owned, root=0),
           "halo": comm.gather(sim.store.n_halo, root=0),
           "messages_per_step": comm.gather(counting.messages / per, root=0),
           "bytes_per_step": comm.gather(counting.bytes / per, root=0),
           "collectives_per_step": comm.gather(counting.collectives / per, root=0),
           "face_particles": round(face)}
    if comm.Get_size() == 2:
        rec["network"] = network(comm)
    if comm.Get_rank() == 0:
        print(json.dumps(rec))


def worker(n: int) -> None:
    w, hgt, steps = SIZES[n]
    measure_step(BLOCK.format(n=n, w=w, hgt=hgt), steps)


def network(comm) -> dict:
    """Ping-pong latency and bandwidth between ranks 0 and 1, 8-byte allreduce latency."""
    import numpy as np
    from mpi4py import MPI

    rank = comm.Get_rank()
    out = {}
    for size in (8, 1 << 20):
        buf = np.zeros(size // 8)
        reps = 2000 if size == 8 else 100
        comm.Barrier()
        t0 = time.perf_counter()
        for _ in range(reps):
            if rank == 0:
                comm.Send(buf, dest=1)
                comm.Recv(buf, source=1)
            else:
                comm.Recv(buf, source=0)
                comm.Send(buf, dest=0)
        out[size] = (time.perf_counter() - t0) / (2 * reps)
    one, total = np.ones(1), np.zeros(1)
    comm.Barrier()
    t0 = time.perf_counter()
    for _ in range(2000):
        comm.Allreduce(one, total, op=MPI.SUM)
    allreduce = (time.perf_counter() - t0) / 2000
    alpha = out[8]
    return {"alpha_s": alpha, "beta_Bps": (1 << 20) / max(out[1 << 20] - alpha, 1e-12),
            "alpha_coll_s": allreduce}


MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none", "NUMBA_NUM_THREADS": "1",
           "OMP_NUM_THREADS": "1"}


def measure_workers(script: str, sizes) -> dict:
    """`script --worker N` under mpirun on 1, 2 and 4 ranks for each size N: the runs'
    records (the last stdout line of each, JSON)."""
    env = dict(os.environ, **MPI_ENV)
    runs = []
    for n in sizes:
        for r in (1, 2, 4):
            cmd = ["mpirun", "-n", str(r), sys.executable, script, "--worker", str(n)]
            res = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
            runs.append(json.loads(res.stdout.strip().splitlines()[-1]))
            print(f"  measured N = {runs[-1]['particles']:,} on {r} rank(s): "
                  f"{runs[-1]['seconds_per_step'] * 1e3:.2f} ms/step, halo "
                  f"{max(runs[-1]['halo']):,} on the largest rank", flush=True)
    return {"date": str(date.today()), "machine": platform.node(), "cpus": os.cpu_count(),
            "runs": runs}


def measure(quick: bool = False) -> dict:
    return measure_workers(__file__, N_QUICK if quick else N_CHECK)


def fit(data: dict) -> dict:
    """The model's constants from the runs: c from one rank, c_h from two, traffic from
    the 2-rank counts (per face, per halo particle), the network from the ping-pong."""
    runs = {(r["particles"], r["ranks"]): r for r in data["runs"]}
    net = next(r["network"] for r in data["runs"] if "network" in r)
    sizes = sorted({r["particles"] for r in data["runs"]})
    c = sum(runs[n, 1]["seconds_per_step"] / n for n in sizes) / len(sizes)
    two = [runs[n, 2] for n in sizes]
    # one face per rank on 2 ranks: bytes per halo particle sent, messages, collectives
    bytes_per_halo = sum(max(r["bytes_per_step"]) / max(r["halo"]) for r in two) / len(two)
    messages = max(max(r["messages_per_step"]) for r in two)
    collectives = max(max(r["collectives_per_step"]) for r in two)
    # what the owned particles at c and the messages leave of a 2-rank step, fitted by
    # least squares as a slower particle-step where ranks share a node (memory bandwidth:
    # c (1 + share)) plus a cost per halo row
    extra, basis = [], []
    for r in two:
        comm_s = messages * net["alpha_s"] + max(r["bytes_per_step"]) / net["beta_Bps"] \
            + collectives * net["alpha_coll_s"]
        extra.append(r["seconds_per_step"] - c * max(r["owned"]) - comm_s)
        basis.append([c * max(r["owned"]), max(r["halo"])])
    import numpy as np

    (share, per_halo), *_ = np.linalg.lstsq(np.array(basis), np.array(extra), rcond=None)
    # the 2-rank halo is 0.3-1.5 % of the owned rows: too small to resolve its cost, so
    # no less than half a particle-step is assumed (its pairs with owned rows are swept)
    return {"c_s": c, "c_halo_fit_s": float(per_halo),
            "c_halo_s": max(float(per_halo), HALO_SHARE * c), "node_share": float(share),
            "bytes_per_halo_particle": bytes_per_halo,
            "messages_per_face": messages, "collectives": collectives, "network": net}


def step_time(k: dict, net: dict, n: float, p: int, face: float, cores: int = 10**9) -> float:
    """Modelled seconds per step of N particles on P ranks (faces: 2, or 1 at P = 2)."""
    if p == 1:
        return k["c_s"] * n
    faces = 1 if p == 2 else 2
    halo = faces * face * HALO_ROWS
    compute = (k["c_s"] * (1.0 + k["node_share"]) * n / p + k["c_halo_s"] * halo) \
        * max(1.0, p / cores)
    traffic = faces * (k["messages_per_face"] * net["alpha_s"]
                       + k["bytes_per_halo_particle"] * face * HALO_ROWS / net["beta_Bps"])
    return compute + traffic + k["collectives"] * math.ceil(math.log2(p)) * net["alpha_coll_s"]


def check(data: dict, k: dict) -> list[dict]:
    rows = []
    for r in data["runs"]:
        p, n = r["ranks"], r["particles"]
        model = step_time(k, k["network"], n, p, r["face_particles"], data["cpus"])
        rows.append({"particles": n, "ranks": p, "measured_ms": 1e3 * r["seconds_per_step"],
                     "model_ms": 1e3 * model,
                     "error": model / r["seconds_per_step"] - 1.0})
    return rows


def projections(k: dict) -> dict:
    out = {}
    for label, net in (("this machine", k["network"]), ("InfiniBand-class", CLUSTER)):
        for n in (1e7, 1e8):
            face = math.sqrt(n / ASPECT)
            p_max = int(math.sqrt(n * ASPECT) / HALO_ROWS)  # slab no thinner than the halo
            t1 = step_time(k, net, n, 1, face)
            strong = []
            for p in P_TABLE:
                if p > p_max:
                    continue
                t = step_time(k, net, n, p, face)
                strong.append({"ranks": p, "ms_per_step": 1e3 * t, "efficiency": t1 / (p * t),
                               "halo_over_owned": (0 if p == 1 else 1 if p == 2 else 2)
                               * face * HALO_ROWS / (n / p)})
            out[f"{label}, N = {n:.0e}"] = {"network": label, "particles": n,
                                            "slab_cap_ranks": p_max, "strong": strong}
        for per in (1e5, 1e6):
            weak = []
            for p in P_TABLE:
                n = per * p
                face = math.sqrt(n / ASPECT)
                weak.append({"ranks": p, "ms_per_step": 1e3 * step_time(k, net, n, p, face),
                             "efficiency": step_time(k, net, per, 1, face)
                             / step_time(k, net, n, p, face)})
            out[f"{label}, weak {per:.0e} per rank"] = {"network": label, "weak": weak}
    return out


def report(data: dict, out: Path = OUT) -> None:
    k = fit(data)
    data["fit"], data["check"], data["model"] = k, check(data, k), projections(k)
    net = k["network"]
    print(f"\nconstants: c = {k['c_s'] * 1e9:.0f} ns per particle-step, halo row cost "
          f"{k['c_halo_s'] * 1e9:.0f} ns (fitted {k['c_halo_fit_s'] * 1e9:.0f}), "
          f"particle-steps {100 * k['node_share']:.1f} % slower "
          f"on a shared node, {k['bytes_per_halo_particle']:.0f} B per halo "
          f"particle, {k['messages_per_face']:.1f} messages per face and "
          f"{k['collectives']:.2f} collectives per step; here alpha = "
          f"{net['alpha_s'] * 1e6:.2f} us, beta = {net['beta_Bps'] / 1e9:.2f} GB/s, "
          f"allreduce {net['alpha_coll_s'] * 1e6:.2f} us")
    print(f"\n{'N':>9} {'ranks':>5} {'measured ms':>12} {'model ms':>9} {'error':>7}")
    for r in data["check"]:
        print(f"{r['particles']:9,d} {r['ranks']:5d} {r['measured_ms']:12.2f} "
              f"{r['model_ms']:9.2f} {100 * r['error']:6.1f}%")
    for name, m in data["model"].items():
        rows = m.get("strong") or m.get("weak")
        cap = f", slab cap {m['slab_cap_ranks']:,} ranks" if "slab_cap_ranks" in m else ""
        print(f"\n{name}{cap}")
        print(f"{'ranks':>6} {'ms/step':>10} {'efficiency':>11}"
              + (f" {'halo/owned':>11}" if "strong" in m else ""))
        for r in rows:
            extra = f" {r['halo_over_owned']:11.3f}" if "strong" in m else ""
            print(f"{r['ranks']:6d} {r['ms_per_step']:10.2f} {100 * r['efficiency']:10.1f}%"
                  + extra)
    (out / "scaling_model.json").write_text(json.dumps(data, indent=2) + "\n")
    plot(data, out)
    print(f"wrote {out / 'scaling_model.json'} and {out / 'scaling_model.png'}")


def plot(data: dict, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for name, m in data["model"].items():
        rows = m.get("strong") or m.get("weak")
        ax = ax1 if "strong" in m else ax2
        ax.semilogx([r["ranks"] for r in rows], [100 * r["efficiency"] for r in rows],
                    "o-" if "InfiniBand" in name else "s--", label=name, base=2)
    for ax, title in ((ax1, "strong scaling (model)"), (ax2, "weak scaling (model)")):
        ax.set_xlabel("ranks")
        ax.set_ylabel("parallel efficiency (%)")
        ax.set_title(title)
        ax.set_ylim(0, 105)
        ax.legend(fontsize=7)
    fig.suptitle(f"psph 2D slabs, section L/H = {ASPECT:g}, {data['date']}, {data['machine']}",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "scaling_model.png", dpi=120)
    plt.close(fig)


def bench_main(doc: str, name: str, worker, measure, report) -> None:
    """The command line of a scaling model: measure (or `--model-only`: read
    <out>/<name>.json back), then `report`; `--worker N` is one mpirun measurement."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--worker", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--model-only", action="store_true",
                    help=f"refit and redraw from <out>/{name}.json")
    ap.add_argument("--quick", action="store_true",
                    help="two small blocks instead of the three sizes (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON and PNG (default bench/out)")
    args = ap.parse_args()
    if args.worker:
        worker(args.worker)
        return
    args.out.mkdir(parents=True, exist_ok=True)
    data = json.loads((args.out / f"{name}.json").read_text()) if args.model_only \
        else measure(args.quick)
    report(data, args.out)


def main() -> None:
    bench_main(__doc__, "scaling_model", worker, measure, report)


if __name__ == "__main__":
    main()

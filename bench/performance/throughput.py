"""Throughput of the coupled elastic step (TPI) in 2D and 3D, of the elastoplastic
collapse step in 3D, and steps/s of the Terzaghi column.

Run under mpirun with the rank count to measure, e.g.
    mpirun -n 1 .venv/bin/python bench/performance/throughput.py
    mpirun -n 2 .venv/bin/python bench/performance/throughput.py
Each run prints a table and writes <out>/throughput-<ranks>rank.json (`--out`, default
bench/out); then `python bench/performance/throughput.py --plot` draws <out>/throughput.png
from all of them. `--quick`: the smallest 2D block for 5 steps alone, into
throughput-quick-<ranks>rank.json (a smoke check).
Particle-steps per second per core = particles * steps / loop wall time / ranks.

The column is the `terzaghi` scene under TPI from t = 0 with its top drained from t = 0 (a
consolidating column: under the impervious loaded top TPI has no storage to answer the
load, and it blows up within a few hundred steps). Every case checks that the state is
still sound after the timed steps.
"""

import argparse
import json
import platform
import sys
import time
import tomllib
from datetime import date
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "out"

BLOCK = """
name = "throughput_{n}"
[domain]
min = [0.0, 0.0]
max = [{w}, {hgt}]
[particles]
dx = 0.01
h_factor = 1.3
[[particles.blocks]]
min = [0.0, 0.0]
max = [{w}, {hgt}]
[material]
E = 20.0e6
nu = 0.33
porosity = 0.4
rho_s = 2000.0
k = 2.0e-4
[boundaries]
left = {{ motion = "slip" }}
right = {{ motion = "slip" }}
bottom = {{ motion = "fixed" }}
top = {{ motion = "free", flow = "drained" }}
[[loads]]
pressure = 1.0e4
ramp = 0.001
[pressure]
scheme = "tpi"
alpha = 0.5
[time]
dt = 5.0e-6
end = 1.0
[stabilisation]
damping = 0.02
"""

# the same soil and step in 3D: a w x w x hgt block between four slip walls, at
# the 2D rows' h = 1.3 dx and at h = 1.2 dx, the default that every shipped 3D scene runs
# at (on the lattice, 80 neighbours within 2h at 1.3 dx against 56 at 1.2 dx)
BLOCK_3D = """
name = "throughput_3d_{n}_h{hf}"
[domain]
min = [0.0, 0.0, 0.0]
max = [{w}, {w}, {hgt}]
[particles]
dx = 0.01
h_factor = {hf}
[[particles.blocks]]
min = [0.0, 0.0, 0.0]
max = [{w}, {w}, {hgt}]
[material]
E = 20.0e6
nu = 0.33
porosity = 0.4
rho_s = 2000.0
k = 2.0e-4
[boundaries]
left = {{ motion = "slip" }}
right = {{ motion = "slip" }}
front = {{ motion = "slip" }}
back = {{ motion = "slip" }}
bottom = {{ motion = "fixed" }}
top = {{ motion = "free", flow = "drained" }}
[[loads]]
pressure = 1.0e4
ramp = 0.001
[pressure]
scheme = "tpi"
alpha = 0.5
[time]
dt = 5.0e-6
end = 1.0
[stabilisation]
damping = 0.02
"""

# a dry Drucker-Prager cube released on a fixed floor, a quarter between two symmetry
# planes (the collapse_3d set-up): the elastoplastic step of a 3D collapse
COLLAPSE_3D = """
name = "throughput_collapse_3d_{n}"
gravity = [0.0, 0.0, -9.81]
[domain]
min = [0.0, 0.0, 0.0]
max = [{far}, {far}, {w}]
[particles]
dx = 0.02
[[particles.blocks]]
min = [0.0, 0.0, 0.0]
max = [{w}, {w}, {w}]
[material]
model = "drucker_prager"
E = 20.0e6
nu = 0.33
porosity = 0.35
rho_s = 2650.0
k = 2.0e-4
[material.plasticity]
phi = 25.0
c = 5.0e3
c_r = 1.0e3
eta = 5.0
psi = 0.0
[boundaries]
left = {{ motion = "slip" }}
front = {{ motion = "slip" }}
bottom = {{ motion = "fixed" }}
[initial]
k0 = 0.577
[pressure]
scheme = "none"
[time]
end = 1.0
[stabilisation]
av_alpha = 1.0
"""


def measure(sim, steps: int, warm: int) -> float:
    for _ in range(warm):
        sim.advance_one()
    sim.slabs.comm.Barrier()
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.advance_one()
    sim.slabs.comm.Barrier()
    seconds = time.perf_counter() - t0
    failed = sim.slabs.comm.allreduce(sim.failure is not None)
    if failed:
        raise SystemExit(f"{sim.scene.name}: the timed run failed ({sim.failure}); "
                         "its steps/s would not be a throughput")
    return seconds


def _bytes(sim) -> float:
    """The running state's bytes per owned particle (store, scratch, pair lists), the
    largest over the ranks (`Simulation.state_bytes`)."""
    return sim.slabs.allreduce_max(sim.state_bytes() / max(sim.store.n_owned, 1))


def main(out: Path = OUT, quick: bool = False) -> None:
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.config.load import load_scene, resolve, validate
    from psph.solver.simulation import Simulation

    comm = MPI.COMM_WORLD
    ranks = comm.Get_size()
    rows = []
    blocks = ((0.2, 0.4, 5),) if quick else ((1.0, 2.0, 60), (2.0, 5.0, 15))
    for side_w, side_h, steps in blocks:
        text = BLOCK.format(n=int(side_w * side_h * 1e4), w=side_w, hgt=side_h)
        scene = resolve(validate(tomllib.loads(text)))
        sim = Simulation(scene, make_slabs(scene, comm))
        secs = measure(sim, steps, warm=3)
        rate = sim.n_global * steps / secs
        rows.append({"case": f"coupled elastic TPI step, N = {sim.n_global}",
                     "particles": sim.n_global, "steps": steps, "seconds": secs,
                     "particle_steps_per_s_per_core": rate / ranks,
                     "steps_per_s": steps / secs, "bytes_per_particle": _bytes(sim)})
    for w, hgt, steps, hf in () if quick else ((0.2, 0.4, 10, 1.3), (0.3, 0.6, 5, 1.3),
                                               (0.3, 0.6, 5, 1.2)):
        text = BLOCK_3D.format(n=int(round(w * w * hgt * 1e6)), w=w, hgt=hgt, hf=hf)
        scene = resolve(validate(tomllib.loads(text)))
        sim = Simulation(scene, make_slabs(scene, comm))
        secs = measure(sim, steps, warm=2)
        # the 1.3 dx rows keep their name, which compare_revisions.py matches across commits
        at = "" if hf == 1.3 else f" at h = {hf} dx"
        rows.append({"case": f"3D coupled elastic TPI step{at}, N = {sim.n_global}",
                     "dim": 3, "h_factor": hf,
                     "particles": sim.n_global, "steps": steps, "seconds": secs,
                     "particle_steps_per_s_per_core": sim.n_global * steps / secs / ranks,
                     "steps_per_s": steps / secs, "bytes_per_particle": _bytes(sim)})
    if not quick:
        text = COLLAPSE_3D.format(n=27000, w=0.6, far=1.8)
        scene = resolve(validate(tomllib.loads(text)))
        sim = Simulation(scene, make_slabs(scene, comm))
        steps = 10
        secs = measure(sim, steps, warm=2)
        rows.append({"case": f"3D elastoplastic collapse step, N = {sim.n_global}", "dim": 3,
                     "particles": sim.n_global, "steps": steps, "seconds": secs,
                     "particle_steps_per_s_per_core": sim.n_global * steps / secs / ranks,
                     "steps_per_s": steps / secs, "bytes_per_particle": _bytes(sim)})
        scene = load_scene("terzaghi_tpi", ["pressure.explicit_until=0.0",
                                            "boundaries.top.drained_from=0.0"])
        sim = Simulation(scene, make_slabs(scene, comm))
        steps = 20000
        secs = measure(sim, steps, warm=200)
        rows.append({"case": f"Terzaghi column (TPI), N = {sim.n_global}",
                     "particles": sim.n_global, "steps": steps, "seconds": secs,
                     "particle_steps_per_s_per_core": sim.n_global * steps / secs / ranks,
                     "steps_per_s": steps / secs, "bytes_per_particle": _bytes(sim)})
    if comm.Get_rank() == 0:
        print(f"\npsph throughput on {ranks} rank(s), {platform.processor() or 'cpu'}, "
              f"{date.today()}")
        print(f"{'case':58s} {'steps':>6s} {'wall s':>8s} {'p-steps/s/core':>15s} "
              f"{'steps/s':>9s} {'bytes/particle':>14s}")
        for r in rows:
            print(f"{r['case']:58s} {r['steps']:6d} {r['seconds']:8.3f} "
                  f"{r['particle_steps_per_s_per_core']:15,.0f} {r['steps_per_s']:9.1f} "
                  f"{r['bytes_per_particle']:14,.0f}")
        out.mkdir(parents=True, exist_ok=True)
        meta = {"date": str(date.today()), "ranks": ranks, "machine": platform.node(),
                "python": sys.version.split()[0], "rows": rows}
        path = out / f"throughput-{'quick-' if quick else ''}{ranks}rank.json"
        path.write_text(json.dumps(meta, indent=2) + "\n")
        print(f"wrote {path}")


def plot(out: Path = OUT) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = [json.loads(p.read_text()) for p in sorted(out.glob("throughput-[0-9]*rank.json"))]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 4.5))
    for run in runs:
        blocks = [r for r in run["rows"] if r["case"].startswith("coupled")]
        blocks_3d = [r for r in run["rows"] if r["case"].startswith("3D coupled")
                     and r.get("h_factor", 1.3) == 1.3]
        others_3d = [r for r in run["rows"] if r["case"].startswith("3D")
                     and r not in blocks_3d]
        col = [r for r in run["rows"] if r["case"].startswith("Terzaghi")]
        a1.plot([r["particles"] for r in blocks],
                [r["particle_steps_per_s_per_core"] / 1e6 for r in blocks], "o-",
                label=f"{run['ranks']} rank(s), 2D")
        if blocks_3d:
            a1.plot([r["particles"] for r in blocks_3d],
                    [r["particle_steps_per_s_per_core"] / 1e6 for r in blocks_3d], "s--",
                    label=f"{run['ranks']} rank(s), 3D elastic")
        for r in others_3d:
            if "collapse" in r["case"]:
                m, what = "v", "collapse (h = 1.2 dx)"
            else:
                m, what = "^", f"elastic, h = {r['h_factor']} dx"
            a1.plot(r["particles"], r["particle_steps_per_s_per_core"] / 1e6, m,
                    label=f"{run['ranks']} rank(s), 3D {what}")
        a2.bar(str(run["ranks"]), col[0]["steps_per_s"])
    a1.axhline(1.0, ls="--", c="grey", label="bar: 1e6")
    a1.axhline(0.5, ls=":", c="grey", label="3D coupled bar: 0.5e6")
    a1.set_xscale("log")
    a1.set_xlabel("particles")
    a1.set_ylabel("million particle-steps / s / core")
    a1.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    a1.set_title("coupled elastic TPI step (h = 1.3 dx unless marked)")
    a2.axhline(1500, ls="--", c="grey")
    a2.set_xlabel("ranks")
    a2.set_ylabel("steps / s")
    a2.set_title("Terzaghi column, 1000 particles")
    fig.suptitle(f"psph throughput, {runs[0]['date'] if runs else ''}")
    fig.tight_layout()
    fig.savefig(out / "throughput.png", dpi=110)
    print(f"wrote {out / 'throughput.png'}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plot", action="store_true",
                    help="draw <out>/throughput.png from the JSON files of earlier runs")
    ap.add_argument("--quick", action="store_true",
                    help="the smallest 2D block for 5 steps alone (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON and PNG (default bench/out)")
    args = ap.parse_args()
    if args.plot:
        plot(args.out)
    else:
        main(args.out, args.quick)

"""One run: output directory, simulation, scheduled callbacks, summary."""

import json
import math
import time
from pathlib import Path

import numpy as np

from psph.decomposition.slabs import Slabs, slab_cuts
from psph.io.snapshots import SnapshotWriter, write_xdmf
from psph.physics.initial import initial_particles
from psph.scene import Scene, to_toml
from psph.solver import Simulation
from psph.verify import reference_times
from psph.verify.errors import TerzaghiMonitor


def _slab_axis(scene: Scene) -> int:
    if scene.decomposition.axis != "auto":
        return {"x": 0, "y": 1}[scene.decomposition.axis]
    ext = np.subtract(scene.domain.max, scene.domain.min)
    return int(np.argmax(ext))


def make_slabs(scene: Scene, comm=None) -> Slabs:
    from mpi4py import MPI

    comm = MPI.COMM_WORLD if comm is None else comm
    axis = _slab_axis(scene)
    x = initial_particles(scene)["x"]
    return Slabs(axis, slab_cuts(x[:, axis], comm.Get_size()), comm)


def snapshot_times(scene: Scene) -> list[float]:
    end = scene.time.end
    times = {0.0, end}
    times.update(t for t in scene.output.times if t <= end)
    times.update(t for t in reference_times(scene) if t <= end)
    if scene.output.interval > 0:
        k = 1
        while k * scene.output.interval < end:
            times.add(k * scene.output.interval)
            k += 1
    return sorted(times)


def run(scene: Scene, out: Path, comm=None, quiet: bool = False) -> dict:
    """Run `scene` into `out` (collective). Returns the summary dict (on every rank)."""
    slabs = make_slabs(scene, comm)
    comm = slabs.comm
    rank0 = slabs.rank == 0
    out = Path(out)
    toml_text = to_toml(scene)
    if rank0:
        out.mkdir(parents=True, exist_ok=True)
        (out / "scene.toml").write_text(toml_text)
    comm.Barrier()

    wall0 = time.perf_counter()
    sim = Simulation(scene, slabs)
    writer = SnapshotWriter(out / "particles.h5", comm, scene.dim, toml_text)
    monitor = TerzaghiMonitor(scene, slabs) if scene.verification.reference == "terzaghi" \
        else None
    history = []
    probes = probe_ids(scene)
    pending = snapshot_times(scene)
    end = scene.time.end
    next_hist = 0.0
    from psph.progress import Progress

    progress = Progress(end, enabled=rank0 and not quiet)
    setup_seconds = time.perf_counter() - wall0
    loop0 = time.perf_counter()

    def snapshot():
        writer.write(sim.step, sim.t, sim.store)
        if monitor is not None:
            monitor.snapshot(sim)
        if rank0:
            write_xdmf(out / "particles.xdmf", "particles.h5", writer.entries, scene.dim)
            _write_history(out / "history.csv", history)  # readable if the run stops

    def diagnostics():
        row = _history_row(sim, probes)
        if monitor is not None:
            monitor.history(sim, row)
        if rank0:
            history.append(row)

    try:
        snapshot()
        pending.pop(0)
        diagnostics()
        next_hist += scene.output.history_interval
        while sim.t < end * (1 - 1e-12):
            sim.advance_one()
            if sim.step % 100 == 0:
                sim.check_failure()
            if sim.t >= next_hist:
                sim.check_failure()
                diagnostics()
                while next_hist <= sim.t:
                    next_hist += scene.output.history_interval
            while pending and sim.t >= pending[0] * (1 - 1e-12):
                pending.pop(0)
                sim.check_failure()
                snapshot()
            if sim.step % 32 == 0:
                progress.update(sim.t, sim.step)
        sim.check_failure()
        if pending:
            snapshot()
    finally:
        progress.close()
        writer.close()

    loop_seconds = time.perf_counter() - loop0
    summary = _summary(sim, slabs, setup_seconds, loop_seconds, monitor)
    verification = None
    if rank0 and history:
        from psph.verify import history_errors

        cols = {k: np.array([r.get(k, np.nan) for r in history]) for k in history[0]}
        x0 = initial_particles(scene)["x"] if probes else None
        verification = history_errors(scene, cols, {k: tuple(x0[i]) for k, i in probes.items()})
    verification = comm.bcast(verification, root=0)
    if verification is not None:
        summary["errors"] = verification
    if rank0:
        _write_history(out / "history.csv", history)
        (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def probe_ids(scene: Scene) -> dict[str, int]:
    """Global id of the particle nearest to each `output.probes` point (initial positions)."""
    if not scene.output.probes:
        return {}
    x = initial_particles(scene)["x"]
    return {name: int(np.argmin(np.sum((x - np.asarray(pt)) ** 2, axis=1)))
            for name, pt in scene.output.probes.items()}


def _history_row(sim: Simulation, probes: dict[str, int]) -> dict:
    """One diagnostics row (collective): surface settlement, kinetic energy, max p, and p
    and displacement of each probe particle (its owner contributes, the others add 0)."""
    st = sim.store
    n = st.n_owned
    surf = st.surface[:n] > 0
    local = np.zeros(3 + 3 * len(probes))
    local[0] = -st.u[:n, 1][surf].sum()
    local[1] = float(surf.sum())
    local[2] = 0.5 * np.sum(st.rho[:n] * st.vol[:n] * np.sum(st.v[:n] ** 2, axis=1))
    keys = st.key[:n]
    for k, pid in enumerate(probes.values()):
        hit = np.flatnonzero(keys == pid)
        if len(hit):
            i = hit[0]
            local[3 + 3 * k:6 + 3 * k] = (st.p[i], st.u[i, 0], st.u[i, 1])
    tot = sim.slabs.allreduce_sum(local)
    pmax = sim.slabs.allreduce_max(float(np.max(st.p[:n])) if n else -math.inf)
    row = {"time": sim.t, "step": sim.step,
           "settlement": tot[0] / tot[1] if tot[1] > 0 else 0.0,
           "kinetic_energy": tot[2], "p_max": pmax}
    for k, name in enumerate(probes):
        row[f"p_{name}"] = tot[3 + 3 * k]
        row[f"ux_{name}"] = tot[4 + 3 * k]
        row[f"uy_{name}"] = tot[5 + 3 * k]
    return row


def _write_history(path: Path, rows: list[dict]) -> None:
    if not rows:
        return
    keys = list(rows[0])
    lines = [",".join(keys)] + [",".join(f"{r[k]:.10g}" for k in keys) for r in rows]
    path.write_text("\n".join(lines) + "\n")


def _summary(sim, slabs, setup_seconds, loop_seconds, monitor) -> dict:
    comm = slabs.comm
    stage_local = {s.name: s.seconds for s in sim.stages}
    gathered = comm.allgather(stage_local)
    stages = {name: {"max_s": max(g[name] for g in gathered),
                     "mean_s": sum(g[name] for g in gathered) / len(gathered),
                     "calls": next(s.calls for s in sim.stages if s.name == name)}
              for name in stage_local}
    psteps = sim.n_global * sim.step
    summary = {
        "scene": sim.scene.name,
        "wall_time_s": setup_seconds + loop_seconds,
        "setup_s": setup_seconds,
        "loop_s": loop_seconds,
        "steps": sim.step,
        "end_time_s": sim.t,
        "particles": sim.n_global,
        "ranks": slabs.size,
        "dt": {"main_s": sim.stepping.dt_main, "explicit_s": sim.stepping.dt_explicit,
               **sim.stepping.limits},
        "steps_per_second": sim.step / loop_seconds if loop_seconds > 0 else None,
        "particle_steps_per_second": psteps / loop_seconds if loop_seconds > 0 else None,
        "particle_steps_per_second_per_core":
            psteps / loop_seconds / slabs.size if loop_seconds > 0 else None,
        "stages_run": [s.name for s in sim.stages],
        "stage_seconds": stages,
    }
    if monitor is not None:
        summary["errors"] = monitor.errors()
    return summary

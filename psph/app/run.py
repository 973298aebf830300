"""One run: output directory, simulation, scheduled callbacks, summary."""

import json
import math
import os
import signal
import sys
import time
from pathlib import Path

import numpy as np

from psph.app.memory import check_memory
from psph.app.restart_rules import check_restart_scene
from psph.config.load import to_toml
from psph.config.rules import check_symmetry_planes, is_slope_3d
from psph.config.schema import Scene
from psph.decomposition.boxes import Boxes, choose_layout
from psph.decomposition.slabs import CommReducer, Slabs, cuts_from_counts
from psph.errors import (
    EARLY_STOP_SIGNALS,
    Interrupted,
    NumericalError,
    OutputError,
    SceneError,
    SceneRule,
)
from psph.geometry.lattice import census, extent, probe_ids
from psph.io.checkpoint import read_history, read_restart, write_checkpoint
from psph.io.snapshots import SnapshotWriter, write_xdmf
from psph.io.space import SNAPSHOT_ROW_BYTES, require_space
from psph.kernels.update import SCHEME_NONE, SCHEME_PROJECTION
from psph.solver.boundary import halo_width
from psph.solver.simulation import Simulation
from psph.verify import history_errors, reference_times
from psph.verify.collapse import collapse_verification
from psph.verify.collapse_3d import axisymmetric_verification
from psph.verify.errors import TerzaghiMonitor
from psph.verify.slope_3d import slope_verification

CONTROL_EVERY = 20  # steps between the collective checks (failure, stop signal, wall clock)
STOP_SIGNALS = (signal.SIGTERM, signal.SIGUSR1)


def _slab_axis(scene: Scene) -> int:
    if scene.decomposition.axis != "auto":
        return {"x": 0, "y": 1, "z": 2}[scene.decomposition.axis]
    ext = np.subtract(scene.domain.max, scene.domain.min)
    return int(np.argmax(ext))


def make_slabs(scene: Scene, comm=None) -> Slabs:
    """Slabs with equal counts of the initial particles: counted per lattice coordinate,
    each rank counting a share of the lattice, never built whole (collective). With
    boxes along two axes (`decomposition.cuts`, `box_layout`) these are the slabs the
    particles are seeded in; `Simulation` moves them to their boxes."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD if comm is None else comm
    axis = _slab_axis(scene)
    width = halo_width(scene)
    reducer = CommReducer(comm)
    values, counts = census(scene, axis, reducer)
    cuts = cuts_from_counts(values, counts, comm.Get_size(), width)
    layout = box_layout(scene, comm.Get_size(), reducer, (values, counts))
    if layout is None:
        return Slabs(axis, cuts, comm)
    return Boxes((axis, layout[0]), layout[1], cuts, comm)


def box_layout(scene: Scene, size: int, reducer, census_axis=None
               ) -> tuple[int, tuple[int, int]] | None:
    """(a1, (n0, n1)) of boxes along two axes (`decomposition.boxes.choose_layout`:
    a1 the particles' longest side but the slab axis), or None for slabs (collective:
    the initial particles' extents from the lattice's census). SceneError for
    `decomposition.cuts = "boxes"` on a rank count without two factors > 1."""
    mode = scene.decomposition.cuts
    if mode == "slabs" or size == 1 or (mode == "auto" and choose_layout(
            (1.0, 1.0), size, "boxes") is None):  # no two factors > 1: slabs
        return None
    axis = _slab_axis(scene)
    ext = np.zeros(scene.dim)
    for d in range(scene.dim):
        values, counts = census_axis if d == axis and census_axis is not None \
            else census(scene, d, reducer)
        taken = values[counts > 0]
        ext[d] = np.ptp(taken) if len(taken) else 0.0
    a1 = max((d for d in range(scene.dim) if d != axis), key=lambda d: ext[d])
    shape = choose_layout((ext[axis], ext[a1]), size, mode)
    if shape is None:
        raise SceneError(f"decomposition.cuts = 'boxes': {size} ranks have no factors "
                         "n0 x n1 with both above 1 (run on 4, 6, 8, 9, ... ranks, or cut "
                         "slabs)")
    return None if shape[1] == 1 else (a1, shape)


def _read_restart(path: Path, scene: Scene, comm) -> tuple[dict, dict]:
    """(meta, {"slabs": the layout, "particles": this rank's rows, "removed": its share of
    the removed ids}) of the checkpoint `path`, whose physics must be the scene's
    (collective)."""
    layout = box_layout(scene, comm.Get_size(), CommReducer(comm))
    meta, cuts, particles, removed = read_restart(
        path, comm, _slab_axis(scene), halo_width(scene),
        check=lambda meta: check_restart_scene(meta["scene"], scene, f"--restart {path}"),
        boxes=layout)
    if layout is None:
        slabs = Slabs(_slab_axis(scene), cuts, comm)
    else:
        slabs = Boxes((_slab_axis(scene), layout[0]), layout[1], cuts[0], comm,
                      cuts0=cuts[1], cuts1=cuts[2])
    return meta, {"slabs": slabs, "particles": particles, "removed": removed}


def _check_restart_census(sim: Simulation, path: Path) -> None:
    """The checkpoint's particles are its ids once each (collective; SceneError, exit 2,
    on every rank if not)."""
    try:
        sim.census.check(sim.store.key[:sim.store.n_owned], sim.step, sim.t)
    except NumericalError as e:
        raise SceneError(f"--restart {path}: corrupt checkpoint ({e})") from None


def _check_symmetry_planes(scene: Scene, bounds: np.ndarray) -> None:
    """Every `symmetry = true` side touches the seeded particles, whose extent over all
    ranks is `bounds` (the same on every rank, so every rank raises SceneError, exit 2,
    together)."""
    try:
        check_symmetry_planes(scene, bounds)
    except SceneRule as e:
        raise SceneError(f"scene '{scene.name}': {e.key} = {e.value!r}: {e.rule}") from None


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


class StopRequest:
    """Turns SIGTERM / SIGUSR1 into a flag the time loop polls (collectively) so that all
    ranks stop at the same step after writing a checkpoint. Restores the old handlers."""

    def __init__(self):
        self.signal: int | None = None
        self._old = {}

    def __enter__(self):
        import threading

        if threading.current_thread() is threading.main_thread():
            for sig in STOP_SIGNALS:
                self._old[sig] = signal.signal(sig, self._handle)
        if EARLY_STOP_SIGNALS:  # one came while the process started: honour it
            self.signal = EARLY_STOP_SIGNALS.pop()
            EARLY_STOP_SIGNALS.clear()
        return self

    def _handle(self, signum, frame) -> None:
        self.signal = signum

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        return False


def run(scene: Scene, out: Path, comm=None, quiet: bool = False,
        restart: Path | None = None) -> dict:
    """Run `scene` into `out` (collective), from t = 0 or from the checkpoint `restart`.
    Returns the summary dict (on every rank). Raises Interrupted after a stop signal
    (the checkpoint is written first), NumericalError on a numerical failure."""
    with StopRequest() as stop:  # from the start: a signal during set-up is kept too
        return _run(scene, out, comm, quiet, restart, stop)


def check_output_directory(out: Path, comm) -> None:
    """Rank 0 creates `out`, writes and removes a probe file in it and removes a stale
    `checkpoint.h5.tmp`; if that fails, every rank raises SceneError (exit 2) with one
    line naming the directory and the cause, before any work (collective)."""
    problem = None
    if comm.Get_rank() == 0:
        created = [d for d in (out, *out.parents) if not d.exists()]
        try:
            out.mkdir(parents=True, exist_ok=True)
            probe = out / f".psph-write-test-{os.getpid()}"
            probe.write_bytes(b"")
            probe.unlink()
            # a checkpoint write cut short (the rename is its commit): never valid
            (out / "checkpoint.h5.tmp").unlink(missing_ok=True)
            for d in created:  # leaf first: bad input found later leaves nothing behind
                d.rmdir()
        except OSError as e:
            problem = f"--out {out}: cannot create or write the output directory " \
                      f"({e.strerror or type(e).__name__}{': ' + e.filename if e.filename else ''})"
    problem = comm.bcast(problem, root=0)
    if problem is not None:
        raise SceneError(problem)


def _run(scene: Scene, out: Path, comm, quiet: bool, restart: Path | None,
         stop: StopRequest) -> dict:
    from mpi4py import MPI

    comm = MPI.COMM_WORLD if comm is None else comm
    out = Path(out)
    wall0 = time.perf_counter()  # set-up: checkpoint read, slab cuts, particles, ghosts
    meta, state = None, None
    check_memory(scene, comm)  # before a checkpoint's rows or a lattice are allocated
    if restart is not None:  # read and check before anything is written
        meta, state = _read_restart(restart, scene, comm)
    check_output_directory(out, comm)
    slabs = make_slabs(scene, comm) if state is None else state["slabs"]
    rank0 = slabs.rank == 0
    toml_text = to_toml(scene)

    if meta is None:
        sim = Simulation(scene, slabs)
        n = sim.store.n_owned
        _check_symmetry_planes(scene, extent(sim.store.x[:n], slabs.reducer))
        probes = probe_ids(scene, sim.store.x[:n], sim.store.key[:n], slabs.reducer)
    else:
        sim = Simulation(scene, slabs, state["particles"], t=meta["t"], step=meta["step"],
                         n_ids=meta["n_ids"], removed=state["removed"],
                         removals_done=meta["removals_done"])
        _check_restart_census(sim, restart)
        probes = probe_ids(scene, reducer=slabs.reducer, slab=slabs.slab)
    del state
    # the first output: after every check of the input (exit 2 leaves nothing behind)
    if rank0:
        out.mkdir(parents=True, exist_ok=True)
        (out / "scene.toml").write_text(toml_text)
    comm.Barrier()
    writer = SnapshotWriter(out / "particles.h5", comm, scene.dim, toml_text,
                            resume_step=None if meta is None else sim.step)
    monitor = TerzaghiMonitor(scene, slabs) if scene.verification.reference == "terzaghi" \
        else None
    history = []
    pending = [t for t in snapshot_times(scene) if meta is None or t > sim.t * (1 + 1e-12)]
    end = scene.time.end
    next_hist = 0.0
    if meta is not None:
        next_hist = meta["next_hist"]
        if monitor is not None:
            monitor.restore(meta["monitor"])
        sim.pressure_solve.recycled.restore(meta.get("recycled_guess"))
        if rank0:
            history = read_history(restart)
    ck = scene.checkpoint
    ck_path = out / "checkpoint.h5"
    last_ck_wall = time.perf_counter()
    # (step, t) of the newest complete checkpoint this run can be continued from
    last_ck = None if meta is None else (meta["step"], meta["t"], Path(restart))

    def resume_hint() -> str:
        if last_ck is None:
            return "no checkpoint written yet: free space and run again"
        step, t, path = last_ck
        return (f"the last complete checkpoint is {path} (step {step}, t = {t:.6g} s): "
                f"free space, then continue with --restart {path}")

    def write_failed(path: Path, e: OSError) -> None:
        """A write failed on this rank (a quota the file system does not report): the
        half-written `.tmp` goes, one line names the file and the hint, and on several
        ranks MPI_Abort stops them all here, since the others may already wait inside
        a collective close or barrier that this rank will never reach."""
        tmp = path.with_name(path.name + ".tmp")
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        message = f"cannot write {path}: {e.strerror or e}; {resume_hint()}"
        if comm.Get_size() == 1:
            raise OutputError(message) from None
        print(f"psph: error: {message}", file=sys.stderr, flush=True)
        comm.Abort(OutputError.exit_code)

    def guarded_write(path: Path, nbytes: int, write) -> None:
        """The space check (collective), then the write."""
        require_space(path, nbytes, comm, resume_hint())
        try:
            write()
        except OSError as e:
            write_failed(path, e)

    def side_files_bytes() -> int:
        """Rank 0's rewrite of history.csv and particles.xdmf at each snapshot (the
        CSV is written whole each time; 1.2 kB of XDMF per snapshot)."""
        csv = out / "history.csv"
        return (csv.stat().st_size if csv.exists() else 0) + 80 * len(history) \
            + 1200 * (len(writer.entries) + 1)
    from psph.app.progress import Progress

    progress = Progress(end, enabled=rank0 and not quiet, start_time=sim.t)
    setup_seconds = time.perf_counter() - wall0
    loop0 = time.perf_counter()

    def snapshot():
        sim.census.check(sim.store.key[:sim.store.n_owned], sim.step, sim.t)
        side = side_files_bytes() if rank0 else 0
        guarded_write(out / "particles.h5", sim.n_global * SNAPSHOT_ROW_BYTES + side,
                      lambda: writer.write(sim.step, sim.t, sim.store))
        if monitor is not None:
            monitor.snapshot(sim)
        if rank0:
            for path, write in (
                    (out / "particles.xdmf", lambda p: write_xdmf(
                        p, "particles.h5", writer.entries, scene.dim)),
                    (out / "history.csv", lambda p: _write_history(p, history))):
                try:
                    write(path)  # history.csv: readable if the run stops
                except OSError as e:
                    write_failed(path, e)

    def diagnostics():
        row = _history_row(sim, probes)
        if monitor is not None:
            monitor.history(sim, row)
        if rank0:
            history.append(row)

    def checkpoint():
        nonlocal last_ck_wall, last_ck
        sim.check_failure()  # never save a broken state
        info = {"t": sim.t, "step": sim.step, "n_global": sim.n_global,
                "n_ids": sim.n_ids, "removals_done": sim.removals_done,
                "next_hist": next_hist, "scene": toml_text,
                "monitor": None if monitor is None else monitor.state(),
                "recycled_guess": sim.pressure_solve.recycled.state(),
                "ranks": slabs.size}
        nbytes = 8 * sim.n_global * sim.store.row_width + 8 * (sim.n_ids - sim.n_global) \
            + 400 * len(history)
        guarded_write(ck_path, nbytes, lambda: write_checkpoint(
            ck_path, comm, sim.store, info, history=history if rank0 else None,
            removed=sim.census.removed))
        last_ck_wall = time.perf_counter()
        last_ck = (sim.step, sim.t, ck_path)

    def control() -> bool:
        """Collective: raise a failure seen on any rank; checkpoint when due by wall
        clock; True if a stop signal reached any rank."""
        due = ck.wall_seconds > 0 and time.perf_counter() - last_ck_wall >= ck.wall_seconds
        flags = slabs.allreduce_max_ints([sim.failure is not None,
                                          stop.signal is not None, due])
        if flags[0]:
            sim.raise_failure()
        if flags[2] and not flags[1]:
            checkpoint()
        return bool(flags[1])

    try:
        if meta is None:
            sim.equilibrate()
            snapshot()
            pending.pop(0)
            diagnostics()
            next_hist += scene.output.history_interval
        while sim.t < end * (1 - 1e-12):
            sim.advance_one()
            if sim.step % CONTROL_EVERY == 0 and control():
                checkpoint()
                _finish(sim, slabs, out, history, setup_seconds,
                        time.perf_counter() - loop0, monitor, probes, "interrupted")
                signame = signal.Signals(
                    comm.allreduce(stop.signal or 0, op=MPI.MAX)).name
                raise Interrupted(
                    f"stopped by {signame} at step {sim.step}, t = {sim.t:.6g} s; "
                    f"checkpoint written: continue with --restart {ck_path}")
            if ck.every and sim.step % ck.every == 0:
                checkpoint()
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
        if ck.at_end:
            checkpoint()
    except OutputError:
        try:  # the file system is full: closing may fail too, the line above says why
            writer.close()
        except OSError:
            pass
        raise
    except NumericalError:
        writer.close()
        if rank0:  # the diagnostics up to the failure: how it grew (issue 39)
            try:
                _write_history(out / "history.csv", history)
            except OSError as e:
                write_failed(out / "history.csv", e)
        raise
    except BaseException:
        writer.close()
        raise
    else:
        writer.close()
    finally:
        progress.close()

    return _finish(sim, slabs, out, history, setup_seconds, time.perf_counter() - loop0,
                   monitor, probes, "finished", restart)


def _finish(sim, slabs, out, history, setup_seconds, loop_seconds, monitor, probes, status,
            restart=None) -> dict:
    """Summary (and verification errors) on every rank; rank 0 writes history.csv and
    summary.json. Collective."""
    summary = _summary(sim, slabs, setup_seconds, loop_seconds, monitor)
    summary["status"] = status
    if restart is not None:
        summary["restarted_from"] = str(restart)
    scene = sim.scene
    rank0 = slabs.rank == 0
    verification = None
    if rank0 and history:
        cols = {k: np.array([r.get(k, np.nan) for r in history]) for k in history[0]}
        verification = history_errors(scene, cols, {k: pos for k, (_, pos) in probes.items()})
    if scene.verification.reference == "collapse" and status == "finished":
        axisymmetric = scene.dim == 3 and len(scene.particles.cylinders) == 1
        verify = axisymmetric_verification if axisymmetric else \
            slope_verification if is_slope_3d(scene) else collapse_verification
        verification = verify(out / "particles.h5", scene, slabs.comm)
        if history:
            verification["p_max_Pa"] = max(r["p_max"] for r in history)
            verification["p_min_Pa"] = min(r["p_min"] for r in history)
    verification = slabs.comm.bcast(verification, root=0)
    if verification is not None:
        summary["errors" if "collapse" not in verification else "metrics"] = verification
    if rank0:
        _write_history(out / "history.csv", history)
        (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def _history_row(sim: Simulation, probes: dict[str, tuple[int, tuple]]) -> dict:
    """One diagnostics row (collective): surface settlement, kinetic energy, max p, and p
    and displacement of each probe particle (its owner contributes, the others add 0)."""
    st = sim.store
    n = st.n_owned
    surf = st.surface[:n] > 0
    dim = sim.dim
    w = 1 + dim  # p and u of a probe
    local = np.zeros(3 + w * len(probes))
    local[0] = -st.u[:n, dim - 1][surf].sum()
    local[1] = float(surf.sum())
    local[2] = 0.5 * np.sum(st.rho[:n] * st.vol[:n] * np.sum(st.v[:n] ** 2, axis=1))
    keys = st.key[:n]
    for k, (pid, _) in enumerate(probes.values()):
        hit = np.flatnonzero(keys == pid)
        if len(hit):
            i = hit[0]
            local[3 + w * k] = st.p[i]
            local[4 + w * k:3 + w * (k + 1)] = st.u[i]
    tot = sim.slabs.allreduce_sum(local)
    pmax = sim.slabs.allreduce_max(float(np.max(st.p[:n])) if n else -math.inf)
    pmin = -sim.slabs.allreduce_max(float(-np.min(st.p[:n])) if n else -math.inf)
    row = {"time": sim.t, "step": sim.step,
           "settlement": tot[0] / tot[1] if tot[1] > 0 else 0.0,
           "kinetic_energy": tot[2], "p_max": pmax, "p_min": pmin,
           "imbalance": sim.slabs.imbalance(st)}
    if sim.stepping.scheme_main == SCHEME_PROJECTION:
        row["cg_iterations"] = sim.solve["iterations"]
        row["cg_residual"] = sim.solve["residual"]
    elif sim.stepping.scheme_main != SCHEME_NONE:
        # the same measure at the explicit / TPI pressure (0 before the first step)
        row["mass_balance_residual"] = sim.mass_balance_residual() if sim.step > 0 else 0.0
    for k, name in enumerate(probes):
        row[f"p_{name}"] = tot[3 + w * k]
        for d in range(dim):
            row[f"u{'xyz'[d]}_{name}"] = tot[4 + w * k + d]
    return row


def _write_history(path: Path, rows: list[dict]) -> None:
    if not rows:
        return
    keys = list(rows[0])
    lines = [",".join(keys)] + [",".join(f"{r[k]:.10g}" for k in keys) for r in rows]
    path.write_text("\n".join(lines) + "\n")


def peak_rss_bytes() -> int:
    """Peak resident memory of this process so far (bytes; Linux reports KiB)."""
    import resource

    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def _summary(sim, slabs, setup_seconds, loop_seconds, monitor) -> dict:
    comm = slabs.comm
    stage_local = {s.name: s.seconds for s in sim.stages}
    gathered = comm.allgather(stage_local)
    stages = {name: {"max_s": max(g[name] for g in gathered),
                     "mean_s": sum(g[name] for g in gathered) / len(gathered),
                     "calls": next(s.calls for s in sim.stages if s.name == name)}
              for name in stage_local}
    steps = sim.step - sim.first_step  # this run's share (a restart starts later)
    psteps = sim.n_global * steps
    memory = comm.allgather((peak_rss_bytes(), sim.state_bytes(), sim.store.n_owned))
    layout = slabs.describe()
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
        "steps_this_run": steps,
        "steps_per_second": steps / loop_seconds if loop_seconds > 0 else None,
        "particle_steps_per_second": psteps / loop_seconds if loop_seconds > 0 else None,
        "particle_steps_per_second_per_core":
            psteps / loop_seconds / slabs.size if loop_seconds > 0 else None,
        "stages_run": [s.name for s in sim.stages],
        "memory": {
            "peak_rss_bytes_per_rank": [m[0] for m in memory],
            "state_bytes_per_rank": [m[1] for m in memory],
            "state_bytes_per_owned_particle": max(m[1] / max(m[2], 1) for m in memory),
        },
        "load_balance": {
            "measure": "max/mean particles owned per rank",
            "threshold": sim.scene.decomposition.imbalance_threshold,
            "check_every_steps": sim.scene.decomposition.rebalance_every,
            "rebalances": slabs.rebalances,
            "imbalance_final": slabs.imbalance(sim.store),
            "imbalance_max_seen": slabs.max_imbalance,
            "imbalance_max_after_recut": slabs.max_after_recut,
            "cuts": layout.get("cuts", layout.get("cuts0")),
        },
        "decomposition": {**layout, "halo_rows_per_rank": comm.allgather(sim.store.n_halo),
                          "owned_per_rank": comm.allgather(sim.store.n_owned)},
        "stage_seconds": stages,
    }
    if sim.stepping.scheme_main == SCHEME_PROJECTION:
        sv = sim.solve
        summary["pressure_solve"] = {
            "method": "matrix-free conjugate gradients, Jacobi, exact (rank-independent) "
                      "inner products",
            "tolerance": sim.scene.pressure.tolerance,
            "iterations_mean": sv["iterations_total"] / max(steps, 1),
            "iterations_max": sv["iterations_max"],
            "steps_not_converged": sv["not_converged"],
            "dt_limit_in_force": "dt_solid_eq41" if sim.scene.time.dt is None else "time.dt"}
    if sim.equilibrium:
        summary["equilibrate"] = sim.equilibrium
    if monitor is not None:
        summary["errors"] = monitor.errors()
    return summary

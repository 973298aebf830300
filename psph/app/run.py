"""One run: output directory, simulation, scheduled callbacks, summary."""

import os
import signal
import time
from pathlib import Path

import numpy as np

from psph.app.memory import check_memory
from psph.app.outputs import RunOutputs
from psph.app.restart_rules import check_restart_scene
from psph.config.load import to_toml
from psph.config.rules import check_symmetry_planes
from psph.config.schema import Scene
from psph.decomposition.boxes import Boxes, choose_layout
from psph.decomposition.slabs import CommReducer, Slabs, cuts_from_counts
from psph.errors import EARLY_STOP_SIGNALS, NumericalError, SceneError, SceneRule
from psph.geometry.lattice import census, extent, probe_ids
from psph.io.checkpoint import read_restart
from psph.solver.boundary import halo_width
from psph.solver.simulation import Simulation
from psph.verify import reference_times

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
    check_memory(scene, comm)  # before a checkpoint's rows or a lattice are allocated
    meta, state = (None, None) if restart is None else _read_restart(restart, scene, comm)
    check_output_directory(out, comm)  # before anything is written
    sim, probes = _simulation(scene, comm, meta, state, restart)
    del state
    pending = [t for t in snapshot_times(scene) if meta is None or t > sim.t * (1 + 1e-12)]
    outputs = RunOutputs(sim, out, probes, pending, meta, restart, stop, to_toml(scene),
                         quiet, wall0)
    schedule = outputs.schedule()
    with outputs:
        if meta is None:
            sim.equilibrate()
            outputs.start()
        while sim.t < scene.time.end * (1 - 1e-12):
            sim.advance_one()
            for callback in schedule:
                if callback.due():
                    callback.run()
        outputs.end()
    return outputs.summary("finished")


def _simulation(scene: Scene, comm, meta: dict | None, state: dict | None,
                restart: Path | None) -> tuple[Simulation, dict]:
    """The simulation of a fresh run (its particles seeded here) or of a checkpoint, and
    the probe particles of its history rows (collective)."""
    if meta is None:
        slabs = make_slabs(scene, comm)
        sim = Simulation(scene, slabs)
        n = sim.store.n_owned
        _check_symmetry_planes(scene, extent(sim.store.x[:n], slabs.reducer))
        return sim, probe_ids(scene, sim.store.x[:n], sim.store.key[:n], slabs.reducer)
    slabs = state["slabs"]
    sim = Simulation(scene, slabs, state["particles"], t=meta["t"], step=meta["step"],
                     n_ids=meta["n_ids"], removed=state["removed"],
                     removals_done=meta["removals_done"],
                     trigger_done=meta.get("trigger_done", False))
    _check_restart_census(sim, restart)
    return sim, probe_ids(scene, reducer=slabs.reducer, slab=slabs.slab)

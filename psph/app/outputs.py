"""The run's outputs and controls as callbacks the time loop schedules: snapshots
(particles.h5, particles.xdmf, history.csv), diagnostics rows, checkpoints, the
collective control (a failure on any rank, a stop signal, the wall-clock checkpoint) and
the progress line. Every write is checked for space first; a failed write names its file
and the checkpoint to continue from."""

import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from psph.app.progress import Progress
from psph.app.summary import finish, history_row, write_history
from psph.errors import Interrupted, NumericalError, OutputError
from psph.io.checkpoint import read_history, write_checkpoint
from psph.io.snapshots import SnapshotWriter, write_xdmf
from psph.io.space import SNAPSHOT_ROW_BYTES, require_space
from psph.solver.simulation import Simulation
from psph.verify.errors import TerzaghiMonitor

CONTROL_EVERY = 20  # steps between the collective checks (failure, stop signal, wall clock)
PROGRESS_EVERY = 32  # steps between updates of the progress line


@dataclass
class Callback:
    """An action of the time loop, run after a step when `due()`."""

    name: str
    due: Callable[[], bool]
    run: Callable[[], None]


class RunOutputs:
    """The output directory of one run and the callbacks that fill it (collective).

    Parameters
    ----------
    sim : Simulation
        The run's state on this rank.
    out : Path
        The output directory (checked writable).
    probes : dict
        The probe particles of the history rows, name -> (id, position).
    snapshot_times : list of float
        The times of the snapshots still to write (s).
    meta : dict or None
        The checkpoint's metadata on a restart, else None.
    restart : Path or None
        The checkpoint the run continues from.
    stop : StopRequest
        The flag the stop signals set.
    toml_text : str
        The scene as TOML (scene.toml, and the snapshots' and checkpoints' attribute).
    quiet : bool
        No progress line.
    wall0 : float
        `time.perf_counter()` at the start of the run's set-up.
    """

    def __init__(self, sim: Simulation, out: Path, probes: dict, snapshot_times: list[float],
                 meta: dict | None, restart: Path | None, stop, toml_text: str,
                 quiet: bool, wall0: float):
        self.sim, self.out, self.probes, self.stop = sim, out, probes, stop
        self.comm, self.rank0 = sim.slabs.comm, sim.slabs.rank == 0
        self.scene, self.toml_text, self.restart = sim.scene, toml_text, restart
        self.wall0 = wall0
        self.setup_seconds = 0.0
        if self.rank0:  # the first output: after every check of the input
            out.mkdir(parents=True, exist_ok=True)
            (out / "scene.toml").write_text(toml_text)
        self.comm.Barrier()
        self.writer = SnapshotWriter(out / "particles.h5", self.comm, sim.dim, toml_text,
                                     resume_step=None if meta is None else sim.step)
        self.monitor = TerzaghiMonitor(self.scene, sim.slabs) \
            if self.scene.verification.reference == "terzaghi" else None
        self.history: list[dict] = []
        self.pending = snapshot_times
        self.next_hist = 0.0
        if meta is not None:
            self.next_hist = meta["next_hist"]
            if self.monitor is not None:
                self.monitor.restore(meta["monitor"])
            sim.pressure_solve.recycled.restore(meta.get("recycled_guess"))
            if self.rank0:
                self.history = read_history(restart)
        self.ck_path = out / "checkpoint.h5"
        self.last_ck_wall = time.perf_counter()
        # (step, t, path) of the newest complete checkpoint this run can be continued from
        self.last_ck = None if meta is None else (meta["step"], meta["t"], Path(restart))
        self.progress = Progress(self.scene.time.end, enabled=self.rank0 and not quiet,
                                 start_time=sim.t)

    # ------------------------------------------------------------------ the schedule

    def schedule(self) -> list[Callback]:
        """The callbacks after each step, in this order on every rank."""
        sim, ck = self.sim, self.scene.checkpoint
        return [
            Callback("control", lambda: sim.step % CONTROL_EVERY == 0, self.control),
            Callback("checkpoint", lambda: bool(ck.every) and sim.step % ck.every == 0,
                     self.checkpoint),
            Callback("diagnostics", lambda: sim.t >= self.next_hist, self.diagnostics_due),
            Callback("snapshot", lambda: bool(self.pending)
                     and sim.t >= self.pending[0] * (1 - 1e-12), self.snapshots_due),
            Callback("progress", lambda: sim.step % PROGRESS_EVERY == 0,
                     lambda: self.progress.update(sim.t, sim.step)),
        ]

    def start(self) -> None:
        """At t = 0 of a fresh run: the first snapshot and diagnostics row."""
        self.snapshot()
        self.pending.pop(0)
        self.diagnostics()
        self.next_hist += self.scene.output.history_interval

    def end(self) -> None:
        """After the last step: a snapshot still due, the final checkpoint if asked."""
        self.sim.check_failure()
        if self.pending:
            self.snapshot()
        if self.scene.checkpoint.at_end:
            self.checkpoint()

    def summary(self, status: str) -> dict:
        """summary.json and history.csv (collective)."""
        loop = time.perf_counter() - self.loop0
        return finish(self.sim, self.sim.slabs, self.out, self.history, self.setup_seconds,
                      loop, self.monitor, self.probes, status,
                      self.restart if status == "finished" else None)

    def __enter__(self):
        self.setup_seconds = time.perf_counter() - self.wall0
        self.loop0 = time.perf_counter()
        return self

    def __exit__(self, kind, error, tb) -> bool:
        """Close the snapshots (a full file system may refuse that too: the error already
        says why); after a numerical failure, history.csv up to it."""
        try:
            try:
                self.writer.close()
            except OSError:
                if kind is None or not issubclass(kind, OutputError):
                    raise
            if kind is not None and issubclass(kind, NumericalError) and self.rank0:
                try:
                    write_history(self.out / "history.csv", self.history)
                except OSError as e:
                    self.write_failed(self.out / "history.csv", e)
        finally:
            self.progress.close()
        return False

    # ------------------------------------------------------------------ the callbacks

    def snapshot(self) -> None:
        sim = self.sim
        sim.census.check(sim.store.key[:sim.store.n_owned], sim.step, sim.t)
        side = self.side_files_bytes() if self.rank0 else 0
        self.guarded_write(self.out / "particles.h5",
                           sim.n_global * SNAPSHOT_ROW_BYTES + side,
                           lambda: self.writer.write(sim.step, sim.t, sim.store))
        if self.monitor is not None:
            self.monitor.snapshot(sim)
        if self.rank0:
            for path, write in (
                    (self.out / "particles.xdmf", lambda p: write_xdmf(
                        p, "particles.h5", self.writer.entries, self.scene.dim)),
                    (self.out / "history.csv", lambda p: write_history(p, self.history))):
                try:
                    write(path)  # history.csv: readable if the run stops
                except OSError as e:
                    self.write_failed(path, e)

    def snapshots_due(self) -> None:
        sim = self.sim
        while self.pending and sim.t >= self.pending[0] * (1 - 1e-12):
            self.pending.pop(0)
            sim.check_failure()
            self.snapshot()

    def diagnostics(self) -> None:
        row = history_row(self.sim, self.probes)
        if self.monitor is not None:
            self.monitor.history(self.sim, row)
        if self.rank0:
            self.history.append(row)

    def diagnostics_due(self) -> None:
        sim = self.sim
        sim.check_failure()
        self.diagnostics()
        while self.next_hist <= sim.t:
            self.next_hist += self.scene.output.history_interval

    def checkpoint(self) -> None:
        sim = self.sim
        sim.check_failure()  # never save a broken state
        info = {"t": sim.t, "step": sim.step, "n_global": sim.n_global,
                "n_ids": sim.n_ids, "removals_done": sim.removals_done,
                "trigger_done": sim.trigger_done,
                "next_hist": self.next_hist, "scene": self.toml_text,
                "monitor": None if self.monitor is None else self.monitor.state(),
                "recycled_guess": sim.pressure_solve.recycled.state(),
                "ranks": sim.slabs.size}
        nbytes = 8 * sim.n_global * sim.store.row_width + 8 * (sim.n_ids - sim.n_global) \
            + 400 * len(self.history)
        self.guarded_write(self.ck_path, nbytes, lambda: write_checkpoint(
            self.ck_path, self.comm, sim.store, info,
            history=self.history if self.rank0 else None, removed=sim.census.removed))
        self.last_ck_wall = time.perf_counter()
        self.last_ck = (sim.step, sim.t, self.ck_path)

    def control(self) -> None:
        """Collective: raise a failure seen on any rank; checkpoint when due by wall
        clock; after a stop signal on any rank, checkpoint, summarise and raise
        Interrupted."""
        from mpi4py import MPI

        sim, ck = self.sim, self.scene.checkpoint
        due = ck.wall_seconds > 0 and time.perf_counter() - self.last_ck_wall >= ck.wall_seconds
        flags = sim.slabs.allreduce_max_ints([sim.failure is not None,
                                              self.stop.signal is not None, due])
        if flags[0]:
            sim.raise_failure()
        if flags[2] and not flags[1]:
            self.checkpoint()
        if not flags[1]:
            return
        self.checkpoint()
        self.summary("interrupted")
        signame = signal.Signals(self.comm.allreduce(self.stop.signal or 0, op=MPI.MAX)).name
        raise Interrupted(f"stopped by {signame} at step {sim.step}, t = {sim.t:.6g} s; "
                          f"checkpoint written: continue with --restart {self.ck_path}")

    # ------------------------------------------------------------------ guarded writes

    def resume_hint(self) -> str:
        if self.last_ck is None:
            return "no checkpoint written yet: free space and run again"
        step, t, path = self.last_ck
        return (f"the last complete checkpoint is {path} (step {step}, t = {t:.6g} s): "
                f"free space, then continue with --restart {path}")

    def write_failed(self, path: Path, e: OSError) -> None:
        """A write failed on this rank (a quota the file system does not report): the
        half-written `.tmp` goes, one line names the file and the hint, and on several
        ranks MPI_Abort stops them all here, since the others may already wait inside
        a collective close or barrier that this rank will never reach."""
        tmp = path.with_name(path.name + ".tmp")
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        message = f"cannot write {path}: {e.strerror or e}; {self.resume_hint()}"
        if self.comm.Get_size() == 1:
            raise OutputError(message) from None
        print(f"psph: error: {message}", file=sys.stderr, flush=True)
        self.comm.Abort(OutputError.exit_code)

    def guarded_write(self, path: Path, nbytes: int, write: Callable[[], None]) -> None:
        """The space check (collective), then the write."""
        require_space(path, nbytes, self.comm, self.resume_hint())
        try:
            write()
        except OSError as e:
            self.write_failed(path, e)

    def side_files_bytes(self) -> int:
        """Rank 0's rewrite of history.csv and particles.xdmf at each snapshot (the
        CSV is written whole each time; 1.2 kB of XDMF per snapshot)."""
        csv = self.out / "history.csv"
        return (csv.stat().st_size if csv.exists() else 0) + 80 * len(self.history) \
            + 1200 * (len(self.writer.entries) + 1)

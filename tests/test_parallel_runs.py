"""2-rank runs (pytest-mpi): migration, load balancing, checkpoint/restart, stop signals
and numerical failure. Run with `mpirun -n 2 python -m pytest --with-mpi -m mpi`.

Every verdict is computed on rank 0 and broadcast, so an assertion cannot leave the other
rank waiting in a collective.
"""

import json
import os
import shutil
import signal
import threading
import time

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.errors import Interrupted, NumericalError
from psph.io.checkpoint import read_checkpoint
from psph.io.snapshots import read_snapshots
from tests.helpers import compare_runs, falling_far, shared_tmp

COLUMN = ["particles.dx=0.02", "material.k=8e-4", "time.end=0.02", "verification.tv=[]",
          "output.times=[0.005, 0.012]"]  # explicit loading, drain at 0.01 s, then TPI


def _world():
    from mpi4py import MPI

    return MPI.COMM_WORLD


def _on_rank0(comm, fn):
    """fn() on rank 0 (None elsewhere), broadcast to every rank."""
    return comm.bcast(fn() if comm.Get_rank() == 0 else None, root=0)


@pytest.fixture(scope="module")
def falling_runs(tmp_path_factory):
    """The falling block on 2 ranks with fixed slabs and with load balancing, and on 1
    rank (rank 0 alone) with load balancing on (a no-op there)."""
    from mpi4py import MPI

    comm = _world()
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:  # one writer: another rank could read a half-written file
        falling_far(out)
    comm.Barrier()
    scene_file = str(out / "falling_far.toml")
    fixed = load_scene(scene_file, ["decomposition.rebalance_every=0"])
    balanced = load_scene(scene_file, ["decomposition.rebalance_every=50"])
    summaries = {"fixed": run(fixed, out / "fixed", comm=comm, quiet=True),
                 "balanced": run(balanced, out / "balanced", comm=comm, quiet=True)}
    if comm.Get_rank() == 0:
        run(balanced, out / "one", comm=MPI.COMM_SELF, quiet=True)
    comm.Barrier()
    return out, summaries


@pytest.mark.mpi(min_size=2)
def test_migration_keeps_every_particle_exactly_once(falling_runs):
    """The block falls through the cut: every particle changes rank, and every snapshot
    holds each id exactly once (the run also checks this itself at each output)."""
    out, summaries = falling_runs
    comm = _world()

    def verdict():
        snaps = read_snapshots(out / "fixed" / "particles.h5")
        n = summaries["fixed"]["particles"]
        for s in snaps:
            if not np.array_equal(s["id"], np.arange(n)):
                return f"ids at step {s['step']} are not 0..{n - 1} once each"
        last = snaps[-1]
        cut = summaries["fixed"]["load_balance"]["cuts"][0]
        y, y0 = last["x"][:, 1], last["x"][:, 1] - last["u"][:, 1]
        crossed = np.sum((y0 > cut) & (y < cut))
        started_above = np.sum(y0 > cut)
        if started_above < n // 3 or crossed != started_above:
            return f"{crossed} of {started_above} particles above the cut crossed it"
        return None

    problem = _on_rank0(comm, verdict)
    assert problem is None, problem


@pytest.mark.mpi(min_size=2)
def test_load_balancing_keeps_imbalance_under_1_1(falling_runs):
    out, summaries = falling_runs
    comm = _world()
    fixed = summaries["fixed"]["load_balance"]
    bal = summaries["balanced"]["load_balance"]
    # the mass shift: with fixed slabs the upper rank ends empty
    assert fixed["imbalance_final"] > 1.9, fixed
    assert bal["rebalances"] >= 1, bal
    assert bal["imbalance_final"] < 1.1, bal
    # right after every recut; before one, the check may see more (that triggers it)
    assert bal["imbalance_max_after_recut"] < 1.1, bal

    def verdict():
        # recutting and redistributing changes no particle: same as 1 rank, bitwise
        return compare_runs(out / "one" / "particles.h5", out / "balanced" / "particles.h5")

    problem = _on_rank0(comm, verdict)
    assert problem is None, problem


@pytest.mark.mpi(min_size=2)
def test_census_names_a_lost_or_duplicated_particle():
    """The census compares counts and checksums of the owned ids; when they do not match,
    its second pass names the id owned by the wrong number of ranks, also after a
    removal (a removed id is expected nowhere)."""
    from psph.decomposition.census import Census

    comm = _world()
    rank = comm.Get_rank()
    n = 10
    mine = np.arange(n)[np.arange(n) % 2 == rank]
    census = Census(comm, n)
    census.check(mine, 0, 0.0)  # all there: no error
    dup = np.append(mine, 3) if rank == 0 else mine  # id 3 lives on rank 1 too
    with pytest.raises(NumericalError, match="particle id 3: field id .owned by 2 ranks"):
        census.check(dup, 7, 0.5)
    lost = mine[mine != 4]
    with pytest.raises(NumericalError, match="particle id 4: field id .owned by 0 ranks"):
        census.check(lost, 7, 0.5)
    swapped = np.where(mine == 4, 6, mine)  # 4 lost and 6 twice: the count is right
    with pytest.raises(NumericalError, match="particle id 4: field id .owned by 0 ranks"):
        census.check(swapped, 7, 0.5)
    with pytest.raises(NumericalError, match="particle id -1: .* 1 unknown ids"):
        census.check(np.append(mine, n) if rank == 1 else mine, 7, 0.5)
    gone = mine[mine >= 6]
    assert census.remove(mine[mine < 6]) == 6
    census.check(gone, 8, 0.6)  # the removed ones are expected nowhere
    with pytest.raises(NumericalError, match="particle id 2: field id .owned by 1 ranks "
                                             "instead of 0"):
        census.check(np.append(gone, 2) if rank == 0 else gone, 8, 0.6)


@pytest.mark.mpi(min_size=2)
def test_restart_continues_bitwise_on_same_and_other_rank_count(tmp_path_factory):
    """A checkpoint in the TPI phase (p_prev carried) restarted on 2 ranks and on 1 rank
    gives the same particles as the uninterrupted 2-rank run."""
    from mpi4py import MPI

    comm = _world()
    out = shared_tmp(comm, tmp_path_factory)
    scene = load_scene("terzaghi_tpi", COLUMN + ["checkpoint.every=35600",
                                             "checkpoint.at_end=false"])
    run(scene, out / "full", comm=comm, quiet=True)
    if comm.Get_rank() == 0:
        for name in ("two", "one"):
            shutil.copytree(out / "full", out / name)
    comm.Barrier()
    meta, _ = read_checkpoint(out / "full" / "checkpoint.h5")
    assert meta["step"] == 35600 and meta["t"] > 0.01  # after the switch to TPI
    summary = run(scene, out / "two", comm=comm, quiet=True,
                  restart=out / "two" / "checkpoint.h5")
    assert summary["status"] == "finished" and summary["steps_this_run"] < summary["steps"]
    if comm.Get_rank() == 0:
        run(scene, out / "one", comm=MPI.COMM_SELF, quiet=True,
            restart=out / "one" / "checkpoint.h5")
    comm.Barrier()

    def verdict():
        return (compare_runs(out / "full" / "particles.h5", out / "two" / "particles.h5")
                or compare_runs(out / "full" / "particles.h5", out / "one" / "particles.h5"))

    problem = _on_rank0(comm, verdict)
    assert problem is None, problem


@pytest.mark.mpi(min_size=2)
def test_sigterm_on_one_rank_leaves_a_valid_checkpoint(tmp_path_factory):
    """SIGTERM reaches rank 1 only, mid-run: both ranks stop at the same step after writing
    the checkpoint; restarting from it matches an uninterrupted run bitwise."""
    comm = _world()
    out = shared_tmp(comm, tmp_path_factory)
    long = load_scene("terzaghi_tpi", COLUMN[:2] + ["time.end=0.5", "verification.tv=[]",
                                                "checkpoint.wall_seconds=0"])
    if comm.Get_rank() == 1:
        def kill_when_running():
            while not (out / "cut" / "particles.xdmf").exists():  # first snapshot done
                time.sleep(0.05)
            time.sleep(0.5)
            os.kill(os.getpid(), signal.SIGTERM)

        threading.Thread(target=kill_when_running, daemon=True).start()
    with pytest.raises(Interrupted, match="stopped by SIGTERM at step"):
        run(long, out / "cut", comm=comm, quiet=True)
    meta, arrays = read_checkpoint(out / "cut" / "checkpoint.h5")
    assert 0 < meta["t"] < 0.5 and np.all(np.isfinite(arrays["p"]))
    status = json.loads((out / "cut" / "summary.json").read_text())["status"]
    assert status == "interrupted"

    t_end = f"time.end={meta['t'] + 0.002!r}"
    short = load_scene("terzaghi_tpi", COLUMN[:2] + [t_end, "verification.tv=[]"])
    run(short, out / "cut", comm=comm, quiet=True, restart=out / "cut" / "checkpoint.h5")
    run(short, out / "whole", comm=comm, quiet=True)
    problem = _on_rank0(comm, lambda: compare_runs(
        out / "whole" / "particles.h5", out / "cut" / "particles.h5", last_only=True))
    assert problem is None, problem


@pytest.mark.mpi(min_size=2)
def test_nan_on_one_rank_stops_all_ranks_with_exit_3(tmp_path_factory, monkeypatch, capsys):
    """A NaN put into p on rank 1: every rank returns exit code 3, rank 0 prints one line
    naming step, time, particle id, rank and field; snapshots and the checkpoint written
    before the failure stay readable."""
    from psph.app import cli
    from psph.solver.simulation import Simulation

    comm = _world()
    out = shared_tmp(comm, tmp_path_factory)
    original = Simulation._update

    def poisoned(self):
        original(self)
        if self.slabs.rank == 1 and self.step == 3000:
            top = int(np.argmax(self.store.x[:self.store.n_owned, 1]))
            self.store.p[top] = np.nan

    monkeypatch.setattr(Simulation, "_update", poisoned)
    code = cli.main(["run", "terzaghi_tpi", "--out", str(out / "bad"), "--quiet",
                     "--set", "checkpoint.every=1000", *sum((["--set", s] for s in COLUMN), [])])
    codes = comm.allgather(code)
    assert codes == [3, 3]
    err = capsys.readouterr().err.strip().splitlines()
    if comm.Get_rank() == 0:
        assert len(err) == 1, err
        for words in ("numerical failure: step 300", "t = ", "particle id", "(rank 1)",
                      "field p = nan"):
            assert words in err[0], (words, err[0])
    meta, _ = read_checkpoint(out / "bad" / "checkpoint.h5")
    assert meta["step"] == 3000
    steps = _on_rank0(comm, lambda: [s["step"] for s in
                                     read_snapshots(out / "bad" / "particles.h5")])
    assert steps == [0]

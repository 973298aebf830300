"""1 rank vs 2 ranks: the same scene gives bitwise-identical particles (pytest-mpi).

Run with `mpirun -n 2 python -m pytest --with-mpi -m mpi`. Rank 0 first runs the scene alone
(COMM_SELF), then both ranks run it together; fields are compared by global id. The falling
block moves every particle across the slab cut, so migration is exercised too.
"""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.io.snapshots import read_snapshots
from tests.helpers import SCENES, shared_tmp

COLUMN = ["particles.dx=0.02", "material.k=8e-4", "time.end=0.02", "verification.tv=[]",
          "output.times=[0.005, 0.012]"]  # explicit loading, drain at 0.01 s, then TPI
PROJECTION = ["pressure.scheme='projection'", "time.integrator='symplectic'",
              "time.dt=2.4e-5"]


def falling_block(tmp: Path) -> Path:
    f = tmp / "falling.toml"
    shutil.copyfile(SCENES / "falling.toml", f)
    return f


def _one_vs_two(comm, scene, out: Path, extra: tuple[str, ...] = ()):
    from mpi4py import MPI

    if comm.Get_rank() == 0:
        run(scene, out / "one", comm=MPI.COMM_SELF, quiet=True)
    comm.Barrier()
    summary = run(scene, out / "two", comm=comm, quiet=True)
    assert summary["ranks"] == 2
    problem = None
    if comm.Get_rank() == 0:
        problem = _compare(out / "one" / "particles.h5", out / "two" / "particles.h5", extra)
    # every rank learns the verdict, so a failure cannot leave a rank waiting
    problem = comm.bcast(problem, root=0)
    assert problem is None, problem


def _compare(path_one: Path, path_two: Path, extra: tuple[str, ...] = ()):
    one = read_snapshots(path_one)
    two = read_snapshots(path_two)
    if [s["step"] for s in one] != [s["step"] for s in two]:
        return "different snapshot steps"
    for a, b in zip(one, two, strict=True):
        if not np.array_equal(a["id"], b["id"]):  # every particle exactly once
            return f"ids differ at step {a['step']}"
        for field in ("x", "u", "v", "p", "n", "stress", *extra):
            # tolerance: none. The neighbour order is partition independent.
            if not np.array_equal(a[field], b[field]):
                diff = np.max(np.abs(a[field] - b[field]))
                return f"{field} differs at step {a['step']} (max abs diff {diff:.3e})"
    return None


@pytest.mark.mpi(min_size=2)
def test_consolidation_column_one_vs_two_ranks_bitwise(tmp_path_factory):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    _one_vs_two(comm, load_scene("terzaghi_tpi", COLUMN), out)


# a small dry collapse (400 particles, 2896 steps) with the regularised softening of
# issue 17: l_c = 0.1 m, its support 0.2 m wider than the 2h = 0.12 m of the pair loop, so
# the halo follows 2 l_c; cut along y through the yielding face
REGULARISED = ["domain.max=[3.0, 1.5]", "particles.blocks.0.max=[1.0, 1.0]",
               "particles.dx=0.05", "time.end=0.2", "output.interval=0.1",
               "material.plasticity.eta=50.0", "decomposition.axis='y'",
               "material.plasticity.regularisation={kind='nonlocal', length=0.1}"]


@pytest.mark.mpi(min_size=2)
def test_regularised_softening_one_vs_two_ranks_bitwise(tmp_path_factory):
    """The non-local eps_p (psph/kernels/nonlocal_strain.py) sums the same particles in
    the same order on 1 and 2 ranks; by 0.2 s 25 particles had yielded on both sides of
    the cut (eps_p > 1e-3, y from 0.02 to 0.87 m, before the wall images entered the
    averages; the cut is near y = 0.5 m). With the
    halo left at 2h (not following 2 l_c) x differed by 1.4e-8 m at 0.1 s."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    _one_vs_two(comm, load_scene("collapse_dry", REGULARISED), out,
                extra=("eps_p", "plastic_work"))
    spread = None
    if comm.Get_rank() == 0:
        last = read_snapshots(out / "two" / "particles.h5")[-1]
        y = last["x"][last["eps_p"] > 1e-3, 1]
        spread = (float(y.min()), float(y.max())) if len(y) else (1.0, 0.0)
    lo, hi = comm.bcast(spread, root=0)
    assert lo < 0.3 and hi > 0.7


@pytest.mark.mpi(min_size=2)
def test_falling_block_migrates_bitwise(tmp_path_factory):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:  # one writer: another rank could read a half-written file
        falling_block(out)
    comm.Barrier()
    scene = load_scene(str(out / "falling.toml"))
    _one_vs_two(comm, scene, out)
    crossed = None
    if comm.Get_rank() == 0:
        last = read_snapshots(out / "two" / "particles.h5")[-1]
        y, y0 = last["x"][:, 1], last["x"][:, 1] - last["u"][:, 1]
        cut = np.median(y0)  # the slab cut of 2 ranks
        crossed = int(np.sum((y0 > cut) & (y < cut)))
    # the block fell onto the floor: particles migrated from the upper to the lower rank
    assert comm.bcast(crossed, root=0) >= 10


@pytest.mark.mpi(min_size=2)
def test_shepard_and_eq47_column_one_vs_two_ranks_bitwise(tmp_path_factory):
    """The Shepard pass re-sends the halo, so filtered pressures and (with
    `shepard_stress`) effective stresses match across the cut."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    scene = load_scene("terzaghi_tpi", COLUMN + ["stabilisation.shepard_every=7",
                                             "stabilisation.shepard_stress=true",
                                             "pressure.beta=0.04"])
    _one_vs_two(comm, scene, out)


@pytest.mark.mpi(min_size=2)
def test_removal_of_regions_one_vs_two_ranks_bitwise(tmp_path_factory):
    """Regions removed at given times (tests/test_removal.py) on both ranks' particles."""
    from mpi4py import MPI

    from tests.helpers import falling_far
    from tests.test_removal import REMOVE

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:
        falling_far(out)
    comm.Barrier()
    scene = load_scene(str(out / "falling_far.toml"), REMOVE + ["time.end=0.15"])
    _one_vs_two(comm, scene, out)


@pytest.mark.mpi(min_size=2)
def test_symplectic_step_one_vs_two_ranks_bitwise(tmp_path_factory):
    """The symplectic step refreshes halo velocities after the kick (Slabs.refresh_halo),
    also for particles that migrated in that step's exchange."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:
        falling_block(out)
    comm.Barrier()
    scene = load_scene(str(out / "falling.toml"), ['time.integrator="symplectic"'])
    _one_vs_two(comm, scene, out)
    column = load_scene("terzaghi_tpi", COLUMN + ['time.integrator="symplectic"',
                                             "stabilisation.shepard_every=7"])
    _one_vs_two(comm, column, out / "column")


@pytest.mark.mpi(min_size=2)
def test_gravity_loading_and_stress_regularisation_one_vs_two_ranks_bitwise(
        tmp_path_factory):
    """Issue 13's paths across the slab cut: `initial.equilibrate` (gravity loading before
    t = 0), the Shepard step with the MLS stress filter of the slopes, the viscosity on
    fixed-wall ghost pairs, the symplectic step and particle shifting, on the saturated
    clay block of the basal-sliding test (its free ends fail plastically, so particles
    move and shift)."""
    from mpi4py import MPI

    from bench.studies.sliding import block_scene

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    scene = block_scene(["initial.equilibrate=0.2", "stabilisation.shepard_every=5",
                         "stabilisation.shepard_stress=true",
                         'stabilisation.stress_filter="mls"', "stabilisation.shifting=2.0",
                         "time.end=0.1",
                         "output.interval=0.05"])
    _one_vs_two(comm, scene, out)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("integrator", ["symplectic", "euler"])
def test_pressure_projection_one_vs_two_ranks_bitwise(tmp_path_factory, integrator):
    """The projection's conjugate-gradient solve (issue 14): exact inner products and
    recorded-pair operators make iterates, iteration counts and particles the same bits,
    after the kick and in the one-sweep step."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    scene = load_scene("terzaghi_tpi", COLUMN + PROJECTION + [f"time.integrator='{integrator}'",
                                                          "pressure.allow_unstable=true"])
    _one_vs_two(comm, scene, out)
    if comm.Get_rank() == 0:
        assert_same_cg_counts(out)


def assert_same_cg_counts(out: Path) -> None:
    """The CG statistics of runs `one` and `two` in `out` are equal, and iterated."""
    one = json.loads((out / "one" / "summary.json").read_text())["pressure_solve"]
    two = json.loads((out / "two" / "summary.json").read_text())["pressure_solve"]
    assert one == two and one["iterations_max"] > 5


@pytest.mark.mpi(min_size=2)
def test_each_rank_seeds_only_its_slab(tmp_path_factory):
    """Distributed set-up (issue 15): the census cuts the slabs where `slab_cuts` of all
    particles would, each rank seeds exactly the particles it owns, with the ids and the
    bits of the one-process set-up, and the peak memory of its set-up (census and seeding,
    traced) is about its share of the one-process peak, not all of it."""
    import tracemalloc

    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.decomposition.slabs import slab_cuts
    from psph.physics.initial import initial_particles
    from tests.test_setup import mixed_scene

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:
        mixed_scene(out)
    comm.Barrier()
    initial_particles(load_scene(str(out / "mixed.toml")))  # imports, outside the trace
    scene = load_scene(str(out / "mixed.toml"), ["particles.dx=0.01"])
    tracemalloc.start()
    slabs = make_slabs(scene, comm)
    local = initial_particles(scene, slabs.reducer, slabs.slab)
    split_peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    tracemalloc.start()
    whole = initial_particles(scene)  # all particles, as one process builds them
    whole_peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()

    mine = slabs.owned_mask(whole["x"])
    problems = []
    if len(local["key"]) != mine.sum():
        problems.append(f"{len(local['key'])} particles seeded, {mine.sum()} owned")
    problems += [f"field {k} differs" for k in whole
                 if local[k].tobytes() != whole[k][mine].tobytes()]
    cuts = slab_cuts(whole["x"][:, slabs.axis], comm.Get_size(), 2.0 * scene.h)
    if not np.array_equal(slabs.cuts, cuts):
        problems.append(f"cuts {slabs.cuts} instead of {cuts}")
    share = mine.sum() / len(mine)
    if split_peak > (share + 0.2) * whole_peak:
        problems.append(f"set-up peak {split_peak} B for {share:.2f} of the particles, "
                        f"{whole_peak} B for all")
    problems = sum(comm.allgather(problems), [])  # every rank learns every verdict
    assert not problems, problems
    assert comm.allreduce(len(local["key"])) == len(whole["key"]) > 40000


def _synthetic_checkpoint(path: Path, n: int, old: bool) -> None:
    """A checkpoint of `n` particles at random positions with ids 0..n+9 but for ten
    removed (as `removed_ids`, or as an older file's `alive` mask)."""
    import h5py

    from psph.io.checkpoint import FORMAT
    from psph.state.particles import FIELDS

    rng = np.random.default_rng(5)
    keep = np.sort(rng.permutation(n + 10)[:n])
    with h5py.File(path, "w") as f:
        f.attrs["format"] = FORMAT
        f.attrs["complete"] = 1
        meta = {"n_global": n, "n_ids": n + 10, "t": 0.0, "step": 0}
        f.attrs["meta"] = json.dumps(meta)
        g = f.create_group("particles")
        for fld in FIELDS:
            g[fld.name] = rng.random((n, fld.ncomp) if fld.ncomp > 1 else n)
        g["key"][...] = keep[rng.permutation(n)]
        g["x"][:, 0] = np.round(g["x"][:, 0], 2)  # columns of equal coordinates too
        alive = np.ones(n + 10, np.uint8)
        alive[keep] = 0
        alive = 1 - alive
        if old:
            f["alive"] = alive
        else:
            f["removed_ids"] = np.flatnonzero(alive == 0)[::-1]


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("old", [False, True])
def test_restart_reads_only_this_ranks_share(tmp_path_factory, old):
    """Distributed restart (issue 15): each rank gets exactly its slab's rows, in the
    file's order, the cuts are `slab_cuts` of all positions bit for bit, the removed ids
    are split over the ranks (also from an older checkpoint's `alive` mask), and the
    traced peak of the read is about this rank's share of reading the file whole."""
    import tracemalloc

    from mpi4py import MPI

    from psph.decomposition.census import Census
    from psph.decomposition.slabs import slab_cuts
    from psph.io.checkpoint import read_checkpoint, read_restart

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    n = 60000
    if comm.Get_rank() == 0:
        _synthetic_checkpoint(out / "checkpoint.h5", n, old)
    comm.Barrier()
    read_restart(out / "checkpoint.h5", comm, 0, 0.05)  # imports, outside the trace
    tracemalloc.start()
    meta, cuts, mine, removed = read_restart(out / "checkpoint.h5", comm, 0, 0.05,
                                             chunk=n // 40)
    split_peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    tracemalloc.start()
    _, whole = read_checkpoint(out / "checkpoint.h5")
    whole_peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()

    problems = []
    c = whole["x"][:, 0]
    if cuts.tobytes() != slab_cuts(c, comm.Get_size(), 0.05).tobytes():
        problems.append(f"cuts {cuts}")
    owned = (c >= cuts[comm.Get_rank()]) & (c < cuts[comm.Get_rank() + 1])
    problems += [f"field {k} differs" for k in mine
                 if mine[k].tobytes() != whole[k][owned].tobytes()]
    all_removed = np.sort(np.concatenate(comm.allgather(removed)))
    if not np.array_equal(all_removed, np.sort(whole["removed_ids"])) or \
            len(all_removed) != 10 or meta["n_removed"] != 10:
        problems.append(f"removed ids {all_removed}")
    share = owned.sum() / n
    if split_peak > (share + 0.2) * whole_peak:
        problems.append(f"restart read peak {split_peak} B for {share:.2f} of the "
                        f"particles, {whole_peak} B for all")
    census = Census(comm, meta["n_ids"], removed)
    census.check(mine["key"], 0, 0.0)  # every id once, or removed
    problems = sum(comm.allgather(problems), [])
    assert not problems, problems


@pytest.mark.mpi(min_size=2)
def test_a_restart_read_with_more_chunks_on_one_rank(tmp_path_factory):
    """2001 rows read 1000 at a time: rank 0's share is one chunk, rank 1's two, so rank
    0 takes part in the second exchange with no rows of its own (that empty slice once
    failed its reshape: "unreadable checkpoint" on every rank)."""
    from mpi4py import MPI

    from psph.decomposition.slabs import slab_cuts
    from psph.io.checkpoint import read_checkpoint, read_restart

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:
        _synthetic_checkpoint(out / "checkpoint.h5", 2001, False)
    comm.Barrier()
    _, cuts, mine, _ = read_restart(out / "checkpoint.h5", comm, 0, 0.05, chunk=1000)
    _, whole = read_checkpoint(out / "checkpoint.h5")
    c = whole["x"][:, 0]
    assert cuts.tobytes() == slab_cuts(c, comm.Get_size(), 0.05).tobytes()
    owned = (c >= cuts[comm.Get_rank()]) & (c < cuts[comm.Get_rank() + 1])
    assert all(mine[k].tobytes() == whole[k][owned].tobytes() for k in mine)


@pytest.mark.mpi(min_size=2)
def test_a_restart_read_failing_on_one_rank_stops_every_rank(tmp_path_factory, monkeypatch):
    """A read error on rank 1 only (its share of the rows): every rank raises the same
    SceneError (exit 2) instead of waiting in the next collective."""
    from mpi4py import MPI

    import psph.io.checkpoint as ck
    from psph.errors import SceneError

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:
        _synthetic_checkpoint(out / "checkpoint.h5", 2000, False)
    comm.Barrier()
    original = ck._pack_chunk

    def failing(f, a, b, order, send, col, unreadable):
        if comm.Get_rank() == 1:  # as _pack_chunk turns h5py's OSError into one line
            raise unreadable(OSError("Can't read data (simulated)"))
        return original(f, a, b, order, send, col, unreadable)

    monkeypatch.setattr(ck, "_pack_chunk", failing)
    with pytest.raises(SceneError, match="unreadable checkpoint .Can't read data"):
        ck.read_restart(out / "checkpoint.h5", comm, 0, 0.05, chunk=500)


TWO_MATERIALS = """
name = "two_materials_falling"
gravity = [0.0, -9.81]
[domain]
min = [0.0, 0.0]
max = [0.2, 1.0]
[particles]
dx = 0.02
[[particles.blocks]]
min = [0.0, 0.1]
max = [0.2, 0.4]
[[particles.polygons]]
vertices = [[0.0, 0.4], [0.2, 0.4], [0.2, 0.7], [0.0, 0.7]]
material = "weak"
[[materials]]
name = "soft"
E = 1.0e6
nu = 0.3
porosity = 0.4
rho_s = 2000.0
k = 1.0e-3
[[materials]]
name = "weak"
model = "drucker_prager"
E = 3.0e6
nu = 0.25
porosity = 0.3
rho_s = 2400.0
k = 1.0e-3
plasticity = { phi = 20.0, c = 300.0 }
[boundaries]
left = { motion = "slip" }
right = { motion = "slip" }
bottom = { motion = "fixed" }
[pressure]
scheme = "none"
[time]
end = 0.2
[output]
interval = 0.05
[checkpoint]
every = 1500
at_end = false
"""


@pytest.mark.mpi(min_size=2)
def test_two_materials_migrate_checkpoint_and_restart_bitwise(tmp_path_factory):
    """Issue 16: a block of two materials (the upper one Drucker-Prager) falls across the
    slab cut: on 1 and 2 ranks, and restarted on 2 ranks from a mid-run checkpoint, every
    snapshot field (with `material` and eps_p) is the same bits."""
    import shutil

    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:
        (out / "two_materials.toml").write_text(TWO_MATERIALS)
    comm.Barrier()
    scene = load_scene(str(out / "two_materials.toml"))
    _one_vs_two(comm, scene, out)
    if comm.Get_rank() == 0:
        shutil.copytree(out / "two", out / "restarted")
    comm.Barrier()
    summary = run(scene, out / "restarted", comm=comm, quiet=True,
                  restart=out / "restarted" / "checkpoint.h5")
    problem = None
    if comm.Get_rank() == 0:
        one = read_snapshots(out / "one" / "particles.h5")
        fields = ("x", "u", "v", "p", "n", "stress", "eps_p", "material")
        for other in ("two", "restarted"):
            snaps = read_snapshots(out / other / "particles.h5")
            for a, b in zip(one, snaps, strict=True):
                bad = [f for f in fields if a[f].tobytes() != b[f].tobytes()]
                if bad or not np.array_equal(a["id"], b["id"]):
                    problem = problem or f"{other} step {a['step']}: {bad}"
        last = one[-1]
        y0 = last["x"][:, 1] - last["u"][:, 1]
        if not np.array_equal(last["material"], (y0 > 0.4) * 1):
            problem = problem or "material index not that of the source"
        if not (last["eps_p"][y0 > 0.4].max() > 0 and last["eps_p"][y0 < 0.4].max() == 0):
            problem = problem or "eps_p: only the Drucker-Prager block may yield"
        if not np.sum((y0 > 0.4) & (last["x"][:, 1] < 0.4)) >= 10:
            problem = problem or "no particle crossed the cut"
    problem = comm.bcast(problem, root=0)
    assert problem is None, problem
    assert summary["restarted_from"] is not None and 0 < summary["steps_this_run"]


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("axis", ["x", "y"])
def test_layered_k0_set_up_one_vs_two_ranks_bitwise(tmp_path_factory, axis):
    """The layered overburden (`physics.initial.overburden`) seeded on two slabs is the
    one-process set-up bit for bit: along x a lattice column lies on one rank, along y
    the running sums continue from the rank above."""
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.physics.initial import initial_particles

    comm = MPI.COMM_WORLD
    scene = load_scene(str(SCENES / "two_layers.toml"), [f"decomposition.axis='{axis}'"])
    slabs = make_slabs(scene, comm)
    local = initial_particles(scene, slabs.reducer, slabs.slab)
    whole = initial_particles(scene)
    mine = slabs.owned_mask(whole["x"])
    problems = [f"field {k} differs" for k in whole
                if local[k].tobytes() != whole[k][mine].tobytes()]
    problems = sum(comm.allgather(problems), [])
    assert not problems, problems
    assert slabs.axis == "xy".index(axis) and 0 < mine.sum() < len(mine)


@pytest.mark.mpi(min_size=2)
def test_polyline_boundaries_one_vs_two_ranks_bitwise(tmp_path_factory):
    """Boundary particles of polylines (issue 16) with the slab cut through them: the V
    column (pore pressure, fixed wall, the cut at the V's tip) and the block sliding on a
    friction incline across the cut. Each rank appends the boundary particles of its slab
    plus 4h and averages soil from a 4h halo (psph/solver/boundary.py)."""
    from mpi4py import MPI

    from tests.test_boundary_particles import INCLINE, V_COLUMN

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:
        (out / "v.toml").write_text(V_COLUMN)
        (out / "incline.toml").write_text(INCLINE.format(
            z0=0.341, z1=0.4796, z2=0.5835, z3=0.4449, interval=0.02,
            motion='motion = "friction"\nfriction_angle = 20.0'))
    comm.Barrier()
    axis = ["decomposition.axis='x'"]
    _one_vs_two(comm, load_scene(str(out / "v.toml"), axis + [
        "initial.equilibrate=0.01", "time.end=0.01", "output.interval=0.005"]), out / "v")
    _one_vs_two(comm, load_scene(str(out / "incline.toml"), axis + ["time.end=0.1"]),
                out / "incline")


@pytest.mark.mpi(min_size=2)
def test_halo_refresh_of_one_field_brings_every_owners_value():
    """`Slabs.refresh_halo` of one column (the CG's search direction, `_refresh_one`) and
    of several fields at once: every halo row gets its owner's current value, also rows
    of particles that migrated in the last exchange (the falling block onto its floor)."""
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.solver.simulation import Simulation

    comm = MPI.COMM_WORLD
    scene = load_scene(str(SCENES / "falling.toml"))
    sim = Simulation(scene, make_slabs(scene, comm))
    st, slabs = sim.store, sim.slabs
    migrated = 0
    while sim.step < 5000 and not migrated:
        n_before = st.n_owned
        sim.advance_one()
        slabs.exchange(st, sim.halo)
        migrated = comm.allreduce(int(st.n_owned != n_before), op=MPI.SUM)
    n, nt = st.n_owned, st.n_owned + st.n_halo
    one = np.full(st.cap, np.nan)
    two = np.full((st.cap, 2), np.nan)
    one[:n] = 1.5 * st.key[:n]
    two[:n, 0] = one[:n]
    two[:n, 1] = -one[:n]
    slabs.refresh_halo(one)
    slabs.refresh_halo(two[:, :1], two[:, 1])
    assert migrated and comm.allreduce(st.n_halo, op=MPI.MIN) > 0
    assert np.array_equal(one[n:nt], 1.5 * st.key[n:nt])
    assert np.array_equal(two[n:nt, 0], one[n:nt])
    assert np.array_equal(two[n:nt, 1], -one[n:nt])

"""3D on 1 and 2 ranks (issue 37): the same particles, bit for bit, and the same
conjugate-gradient iterations; a restart on another rank count continues the same bits.

Run with `mpirun -n 2 python -m pytest --with-mpi -m mpi`."""

import json
import shutil

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.io.snapshots import read_snapshots
from tests.helpers import shared_tmp
from tests.test_mpi import _one_vs_two, assert_same_cg_counts

# the Section 4.1 column in 3D at dx = 0.02 m through the loading and the first drainage
COLUMN_3D = ["particles.dx=0.02", "domain.max=[0.08, 0.08, 1.0]",
             "particles.blocks=[{min=[0.0, 0.0, 0.0], max=[0.08, 0.08, 1.0]}]",
             "time.end=0.03", "verification.tv=[]", "output.times=[0.005, 0.012]"]


# the slopes' stabilisation in 3D: the Shepard step with the MLS stress filter, shifting
STABILISED = ["stabilisation.shepard_every=7", "stabilisation.shepard_stress=true",
              "stabilisation.stress_filter='mls'", "stabilisation.shifting=1.0"]


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("axis, extra", [("z", []), ("x", []), ("x", STABILISED)])
def test_terzaghi_3d_one_vs_two_ranks_bitwise(tmp_path_factory, axis, extra):
    """Slabs along the column (z, the default: the longest side) and across it (x: every
    slab holds the whole height, the halo is a vertical plane with edge and corner
    ghosts), and with the Shepard step, the MLS stress filter and particle shifting: every
    field the same bits, the same CG iteration counts."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    scene = load_scene("terzaghi_3d", COLUMN_3D + [f"decomposition.axis='{axis}'"] + extra)
    _one_vs_two(comm, scene, out)
    if comm.Get_rank() == 0:
        assert_same_cg_counts(out)


@pytest.mark.mpi(min_size=2)
def test_terzaghi_3d_restart_on_two_ranks_from_one(tmp_path_factory):
    """A 3D checkpoint written on one rank mid-run, restarted on two: the snapshots after
    it are those of the uninterrupted one-rank run, bit for bit."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    scene = load_scene("terzaghi_3d", COLUMN_3D + ["checkpoint.every=300",
                                                   "checkpoint.at_end=false"])
    if comm.Get_rank() == 0:
        run(scene, out / "one", comm=MPI.COMM_SELF, quiet=True)
        shutil.copytree(out / "one", out / "restarted")
    comm.Barrier()
    summary = run(scene, out / "restarted", comm=comm, quiet=True,
                  restart=out / "restarted" / "checkpoint.h5")
    assert summary["ranks"] == 2 and summary["steps_this_run"] > 0
    problem = None
    if comm.Get_rank() == 0:
        one = read_snapshots(out / "one" / "particles.h5")
        two = read_snapshots(out / "restarted" / "particles.h5")
        a, b = one[-1], two[-1]
        if a["step"] != b["step"] or not np.array_equal(a["id"], b["id"]):
            problem = "different final snapshot"
        for f in ("x", "u", "v", "p", "n", "stress"):
            if a[f].tobytes() != b[f].tobytes():
                problem = problem or f"{f} differs after the restart"
        if a["x"].shape[1] != 3:
            problem = problem or "not a 3D snapshot"
    problem = comm.bcast(problem, root=0)
    assert problem is None, problem


@pytest.mark.mpi(min_size=2)
def test_recycled_guess_one_vs_two_ranks_and_restart_bitwise(tmp_path_factory):
    """Issue 36: the projection's initial guess projected on earlier CG corrections
    (`pressure.recycle`, psph/solver/recycling.py): its basis travels with the particles
    and in checkpoints, so 1 and 2 ranks, and a restart on 2 ranks from a 1-rank
    checkpoint, give the same bits and CG counts; and it cuts the iterations."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    base = ["time.end=0.1", "verification.tv=[]", "output.times=[0.02, 0.05]",
            "checkpoint.every=1200", "checkpoint.at_end=false"]
    scene = load_scene("terzaghi", base + ["pressure.recycle=16"])
    _one_vs_two(comm, scene, out)
    if comm.Get_rank() == 0:
        shutil.copytree(out / "one", out / "restarted")
    comm.Barrier()
    run(scene, out / "restarted", comm=comm, quiet=True,
        restart=out / "restarted" / "checkpoint.h5")
    problem = None
    if comm.Get_rank() == 0:
        a = read_snapshots(out / "one" / "particles.h5")[-1]
        b = read_snapshots(out / "restarted" / "particles.h5")[-1]
        bad = [f for f in ("x", "u", "v", "p", "stress") if a[f].tobytes() != b[f].tobytes()]
        problem = f"restart differs in {bad}" if bad else None
        one = json.loads((out / "one" / "summary.json").read_text())["pressure_solve"]
        two = json.loads((out / "two" / "summary.json").read_text())["pressure_solve"]
        if one != two:
            problem = problem or f"CG counts differ: {one} {two}"
    problem = comm.bcast(problem, root=0)
    assert problem is None, problem
    if comm.Get_rank() == 0:
        run(load_scene("terzaghi", base + ["pressure.recycle=0"]), out / "off",
            comm=MPI.COMM_SELF, quiet=True)
        off = json.loads((out / "off" / "summary.json").read_text())["pressure_solve"]
        assert one["iterations_mean"] < 0.6 * off["iterations_mean"]


@pytest.mark.mpi(min_size=2)
def test_collapse_3d_with_nonlocal_strain_one_vs_two_ranks_bitwise(tmp_path_factory):
    """The dry quarter column (CI size) with the regularised softening of issue 17 in 3D
    (`nonlocal_strain_3d`: the averages over cells in z too, the images across the
    floor and the two symmetry planes, their edges and corner): 1 and 2 ranks, every
    field the same bits."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    scene = load_scene("collapse_3d", [
        "particles.dx=0.1", "time.end=0.15", "output.interval=0.05",
        "material.plasticity.eta=5.0", "material.plasticity.c=5e3",
        "material.plasticity.c_r=1e3",
        "material.plasticity.regularisation={kind='nonlocal', length=0.15, m=2.0}",
        "boundaries.surfaces=[]", "boundaries.bottom={motion='fixed'}"])
    _one_vs_two(comm, scene, out, ("eps_p",))
    if comm.Get_rank() == 0:
        last = read_snapshots(out / "one" / "particles.h5")[-1]
        assert last["eps_p"].max() > 0.0  # the averages ran where the soil yielded


@pytest.mark.mpi(min_size=2)
def test_collapse_3d_on_a_surface_floor_one_vs_two_ranks_bitwise(tmp_path_factory):
    """The dry quarter column (CI size) on its floor, a surface lined with boundary
    particles (`kernels/boundary_3d.py`, halo 4h) with Coulomb friction and the friction
    of the touching particles' weight (`boundary_contact`): 1 and 2 ranks, every field
    the same bits."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    scene = load_scene("collapse_3d", [
        "particles.dx=0.1", "time.end=0.15", "output.interval=0.05"])
    assert scene.boundaries.surfaces[0].weight_friction
    _one_vs_two(comm, scene, out, ())
    if comm.Get_rank() == 0:
        last = read_snapshots(out / "one" / "particles.h5")[-1]
        assert last["x"][:, 2].min() > 0.0 and np.abs(last["v"]).max() > 0.1


@pytest.mark.mpi(min_size=2)
def test_layers_between_elevation_grids_one_vs_two_ranks_bitwise(tmp_path_factory):
    """The two-material column between elevation grids (an .asc, a CSV) with a water
    table grid (`tests/test_grids.py`): at rest for 0.05 s on 1 and 2 ranks, the same
    bits, and within its overburden on both."""
    from mpi4py import MPI

    from tests.test_grids import _layered_scene, _reference

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    if comm.Get_rank() == 0:
        _layered_scene(out)
    comm.Barrier()
    scene = load_scene(str(out / "grid_layers.toml"))
    _one_vs_two(comm, scene, out, ())
    if comm.Get_rank() == 0:
        last = read_snapshots(out / "two" / "particles.h5")[-1]
        sv, p = _reference(last["x"][:, 2] - last["u"][:, 2])
        assert np.max(np.abs(last["p"] - p)) < 0.005 * p.max()
        assert np.max(np.abs(last["stress"][:, 2] - sv)) < 0.02 * np.abs(sv).max()


@pytest.mark.mpi(min_size=2)
def test_slope_3d_cut_to_a_depth_one_vs_two_ranks_bitwise(tmp_path_factory):
    """`slope_3d` coarsened (`tests/test_slope_3d.py`), its toe cut in plan to 6 m below
    each column's top (the columns' tops a maximum over the ranks): the same bits on 1
    and 2 ranks, and the same plan metrics."""
    from mpi4py import MPI

    from tests.test_slope_3d import SHORT

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    cut = ["remove=[{at = 0.0, polygon = [[150.0, 0.0], [200.0, 0.0], [200.0, 9.0], "
           "[150.0, 9.0]], depth = 6.0}]"]
    scene = load_scene("slope_3d", SHORT + cut)
    _one_vs_two(comm, scene, out, ())
    if comm.Get_rank() == 0:
        one, two = (json.loads((out / k / "summary.json").read_text())["metrics"]
                    for k in ("one", "two"))
        assert one["slope_3d"] == two["slope_3d"]
        x = read_snapshots(out / "two" / "particles.h5")[1]
        x0 = x["x"] - x["u"]
        under = (x0[:, 0] > 152.0) & (x0[:, 1] < 9.0)
        ground = 20.0 * (180.0 - x0[under, 0]) / 39.25  # the slope's face there
        assert under.any() and np.all(x0[under, 2] < ground - 6.0)

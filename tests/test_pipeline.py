"""The step pipeline is assembled once from the scene: only the stages it needs run, and
summary.json says which ran and for how long."""

import json

import pytest

from psph.app.run import make_slabs, run
from psph.config.load import load_scene
from psph.solver.simulation import Simulation

SMALL = ["particles.dx=0.05", "verification.tv=[]", "time.end=0.002"]


def _stages(overrides):
    from mpi4py import MPI

    scene = load_scene("terzaghi_tpi", SMALL + overrides)
    return [s.name for s in Simulation(scene, make_slabs(scene, MPI.COMM_SELF)).stages]


@pytest.mark.parametrize("overrides, present, absent", [
    (["pressure.scheme='explicit'", "time.dt=2.8e-7"],
     ["update[explicit,elastic]", "interactions[momentum,pressure]"],
     ["tpi", "shepard", "exchange", "drucker_prager", "rebalance"]),
    (["pressure.explicit_until=0.0", "boundaries.top.drained_from=0.0"],
     ["update[tpi,elastic]"], ["explicit", "shepard"]),
    ([], ["update[explicit->tpi,elastic]"], ["shepard"]),
    (["stabilisation.shepard_every=20"], ["shepard[every 20]"], []),
    (["pressure.scheme='none'", "stabilisation.shepard_every=20"],
     ["interactions[momentum]", "update[dry,elastic]"], ["pressure", "shepard"]),
    # a dry scene filters its stress, if asked, and has no pressure to filter
    (["pressure.scheme='none'", "stabilisation.shepard_every=20",
      "stabilisation.shepard_stress=true", "stabilisation.stress_filter='mls'"],
     ["mls_stress[every 20]"], ["pressure", "shepard"]),
    (["pressure.scheme='none'", "stabilisation.shepard_every=20",
      "stabilisation.shepard_stress=true"], ["shepard_stress[every 20]"], ["pressure"]),
    (["material.model='drucker_prager'", "material.plasticity.phi=30.0"],
     ["update[explicit->tpi,drucker_prager]"], ["elastic"]),
    (["boundaries.left.motion='free'", "boundaries.right.motion='free'",
      "boundaries.bottom.motion='free'"], [], ["ghosts"]),
    # the free drained top is a plane only with the default drained_boundary = "mirror"
    ([], ["drained_planes"], []),
    (["pressure.drained_boundary='layer'"], [], ["drained_planes"]),
    (["boundaries.top.motion='slip'"], [], ["drained_planes"]),  # a wall: its ghosts
])
def test_only_needed_stages(overrides, present, absent):
    names = _stages(overrides)
    joined = " ".join(names)
    for p in present:
        assert p in names, names
    for a in absent:
        assert a not in joined, names


def test_summary_lists_stages_and_times(tmp_path):
    from mpi4py import MPI

    scene = load_scene("terzaghi_tpi", SMALL + ["stabilisation.shepard_every=4"])
    run(scene, tmp_path, comm=MPI.COMM_SELF, quiet=True)
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["stages_run"] == ["reset_halo", "ghosts", "neighbours", "drained_planes",
                               "shepard[every 4]",
                               "interactions[momentum,pressure]", "update[explicit->tpi,elastic]"]
    assert set(s["stage_seconds"]) == set(s["stages_run"])
    steps = s["steps"]
    assert s["stage_seconds"]["neighbours"]["calls"] == steps
    assert s["stage_seconds"]["shepard[every 4]"]["calls"] == (steps + 3) // 4
    assert all(v["max_s"] > 0 for v in s["stage_seconds"].values())

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
    assert s["stages_run"] == ["drained_planes", "reset_halo", "ghosts", "neighbours",
                               "shepard[every 4]", "refresh[p,p_prev][every 4]",
                               "interactions[momentum,pressure]", "update[explicit->tpi,elastic]"]
    assert set(s["stage_seconds"]) == set(s["stages_run"])
    steps = s["steps"]
    assert s["stage_seconds"]["neighbours"]["calls"] == steps
    assert s["stage_seconds"]["shepard[every 4]"]["calls"] == (steps + 3) // 4
    assert s["stage_seconds"]["refresh[p,p_prev][every 4]"]["calls"] == (steps + 3) // 4
    assert all(v["max_s"] > 0 for v in s["stage_seconds"].values())


def _names(stages):
    return [s.name for s in stages]


def test_search_and_refreshes_follow_the_declarations():
    """The search comes before the first stage on neighbours after x moved; a field
    written on owned rows is refreshed before a later stage reads it on neighbours, once,
    and only the fields that stage reads."""
    from psph.solver.pipeline import Stage, assemble

    refreshed = []
    search = [Stage("exchange", lambda: None), Stage("neighbours", lambda: None)]
    physics = [
        Stage("planes", lambda: None),
        Stage("filter", lambda: None, reads=frozenset({"p"}), writes=frozenset({"p"}),
              neighbours=True, every=5),
        Stage("sweep", lambda: None, reads=frozenset({"x", "p", "v"}), neighbours=True),
        Stage("kick", lambda: None, writes=frozenset({"v", "acc"})),
        Stage("velocity", lambda: None, reads=frozenset({"v"}), neighbours=True),
        Stage("shift", lambda: None, reads=frozenset({"vol"}), writes=frozenset({"x"}),
              neighbours=True),
        Stage("update", lambda: None, writes=frozenset({"x", "v", "p"})),
        Stage("after", lambda: None, reads=frozenset({"v"}), neighbours=True),
    ]
    stages = assemble(physics, search, refreshed.append)
    assert _names(stages) == ["planes", "exchange", "neighbours", "filter",
                              "refresh[p][every 5]", "sweep", "kick", "refresh[v]",
                              "velocity", "shift", "update", "exchange", "neighbours",
                              "after"]
    by_name = {s.name: s for s in stages}
    refresh = by_name["refresh[p][every 5]"]
    assert refresh.every == 5 and refresh.after == (by_name["filter"],)
    refresh.run()
    assert refreshed == [("p",)]
    # a derived refresh runs in a pass only when its writer ran in that pass
    assert not refresh.due(0, 1)
    by_name["filter"].last_pass = 1
    assert refresh.due(0, 1) and not refresh.due(0, 2) and not refresh.due(1, 1)


def test_no_physics_stage_searches_or_exchanges():
    """Exchange, ghosts and the neighbour search are called only by the search stages
    and the derived refreshes (`Stages._refresh_fields`), never inside physics."""
    import ast
    import inspect

    from psph.solver import stages

    tree = ast.parse(inspect.getsource(stages))
    allowed = {"_exchange", "_ghosts", "_boundary_rows", "_neighbours", "_boundary_state",
               "_refresh_fields", "_refresh_walls", "_rebalance", "_reset_halo"}
    searching = {"exchange", "refresh_halo", "_ghosts", "_neighbours", "_exchange",
                 "_refresh_walls", "_boundary_rows", "_boundary_state", "make_ghosts",
                 "bin", "rebalance"}
    for fn in ast.walk(tree):
        if not isinstance(fn, ast.FunctionDef) or fn.name in allowed:
            continue
        calls = {c.func.attr if isinstance(c.func, ast.Attribute) else getattr(c.func, "id", "")
                 for c in ast.walk(fn) if isinstance(c, ast.Call)}
        assert not calls & searching, (fn.name, calls & searching)

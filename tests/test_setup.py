"""Distributed set-up (issue 15, item 1): the slab cuts from the per-coordinate census are
`slab_cuts` of all particles, and the slabs seeded rank by rank hold every particle once
with the id and the bits of the one-process set-up. Ranks are threads here (a reducer
over a barrier); tests/test_mpi.py does the same over MPI."""

import threading

import meshio
import numpy as np
import pytest

from psph.config.load import load_scene
from psph.decomposition.slabs import cuts_from_counts, slab_cuts
from psph.geometry.lattice import census, nearest
from psph.physics.initial import initial_particles

SCENE = """
name = "mixed"
gravity = [0.0, -9.81]
[domain]
min = [0.0, 0.0]
max = [6.0, 2.0]
[particles]
dx = 0.05
[[particles.blocks]]
min = [4.0, 0.0]
max = [5.13, 0.6]
[[particles.polygons]]
vertices = [[0.0, 0.0], [1.5, 0.0], [1.5, 1.2], [0.0, 1.4]]
[[particles.meshes]]
file = "{mesh}"
[[particles.layers]]
top = [[2.0, 1.0], [3.5, 0.7], [4.0, 0.7]]
bottom = [[2.0, 0.0], [4.0, 0.0]]
[material]
E = 1.0e7
nu = 0.3
porosity = 0.4
rho_s = 2000.0
k = 1.0e-4
K_l = 1.0e8
[boundaries]
left = {{ motion = "slip" }}
bottom = {{ motion = "fixed" }}
top = {{ flow = "drained" }}
right = {{ flow = "drained" }}
[initial]
water_table = 0.8
k0 = 0.6
[[loads]]
side = "top"
pressure = 1.0e3
range = [0.2, 1.0]
[pressure]
scheme = "explicit"
[time]
end = 0.002
"""


def mixed_scene(directory) -> str:
    """A block, a polygon, a mesh (the test_geometry slope moved to x = 1..4) and a
    layer, with loads, drained sides, a water table and K0: every part of the set-up."""
    pts = np.array([[0, 0], [3, 0], [3, 0.5], [2, 0.5], [1, 1], [0, 1], [1, 0.5]], float)
    cells = [("triangle", np.array([[6, 3, 4]])),
             ("quad", np.array([[0, 1, 2, 3], [0, 3, 6, 5]])),
             ("triangle", np.array([[6, 4, 5]]))]
    mesh = directory / "slope.vtu"
    meshio.write(mesh, meshio.Mesh(np.c_[pts + [1.0, 0.0], np.zeros(len(pts))], cells))
    path = directory / "mixed.toml"
    path.write_text(SCENE.format(mesh=mesh))
    return str(path)


class ThreadRanks:
    """`size` threads as ranks: each reduction gathers every thread's array at a barrier."""

    def __init__(self, size: int):
        self.size = size
        self.barrier = threading.Barrier(size)
        self.slots = [None] * size

    def run(self, work):
        """work(reducer) on every rank; the results in rank order."""
        results, errors = [None] * self.size, []

        def target(rank):
            try:
                results[rank] = work(_Reducer(self, rank))
            except Exception as e:  # noqa: BLE001  (reported below)
                errors.append(e)
                self.barrier.abort()

        threads = [threading.Thread(target=target, args=(r,)) for r in range(self.size)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        if errors:
            raise errors[0]
        return results


class _Reducer:
    def __init__(self, ranks: ThreadRanks, rank: int):
        self.ranks, self.rank, self.size = ranks, rank, ranks.size

    def _gather(self, a) -> list[np.ndarray]:
        self.ranks.slots[self.rank] = np.array(a)
        self.ranks.barrier.wait()
        out = list(self.ranks.slots)
        self.ranks.barrier.wait()
        return out

    def max(self, a):
        return np.max(self._gather(a), axis=0)

    def min(self, a):
        return np.min(self._gather(a), axis=0)

    def sum(self, a):
        return np.sum(self._gather(a), axis=0)

    def exclusive_scan(self, a):
        g = self._gather(a)
        return np.sum(g[:self.rank], axis=0) if self.rank else np.zeros_like(g[0])


def test_cuts_from_counts_are_slab_cuts():
    rng = np.random.default_rng(3)
    for _ in range(20):
        values = rng.choice(rng.uniform(0, 10, 30), 40)  # repeated values
        counts = rng.integers(0, 5, 40)
        coords = np.repeat(values, counts)
        for size in (1, 2, 3, 4, 7):
            assert np.array_equal(cuts_from_counts(values, counts, size, 0.3),
                                  slab_cuts(coords, size, 0.3))


@pytest.mark.parametrize("size,axis", [(2, 0), (3, 0), (5, 0), (3, 1)])
def test_slabs_seeded_apart_are_the_whole_set_up(tmp_path, size, axis):
    scene = load_scene(mixed_scene(tmp_path))
    whole = initial_particles(scene)
    width = 2.0 * scene.h

    def work(reducer):
        cuts = cuts_from_counts(*census(scene, axis, reducer), reducer.size, width)
        data = initial_particles(scene, reducer, (axis, cuts[reducer.rank],
                                                  cuts[reducer.rank + 1]))
        probes = nearest([[0.31, 0.52], [4.5, 0.3], [2.52, 0.41]], data["x"], data["key"],
                         reducer)
        return cuts, data, probes

    results = ThreadRanks(size).run(work)
    cuts = slab_cuts(whole["x"][:, axis], size, width)
    for r, (c, data, _) in enumerate(results):
        assert np.array_equal(c, cuts)
        c_axis = whole["x"][:, axis]
        mine = (c_axis >= cuts[r]) & (c_axis < cuts[r + 1])
        assert len(data["key"]) == mine.sum()  # seeded: exactly the owned particles
        assert set(data) == set(whole)
        for k in whole:
            assert data[k].tobytes() == whole[k][mine].tobytes(), (r, k)
    d2 = [np.sum((whole["x"] - p) ** 2, axis=1) for p in ([0.31, 0.52], [4.5, 0.3],
                                                          [2.52, 0.41])]
    ids, pos = results[0][2]
    assert ids.tolist() == [int(np.argmin(d)) for d in d2]
    assert pos.tobytes() == whole["x"][ids].tobytes()


def test_loaded_half_width_needs_only_the_outer_row(tmp_path):
    from psph.verify.strip import loaded_half_width

    for scene in (load_scene("strip_footing"), load_scene(mixed_scene(tmp_path))):
        loaded = initial_particles(scene)["load_index"] >= 0
        assert loaded_half_width(scene) == float(np.sum(loaded)) * scene.particles.dx


def test_distributed_cuts_are_slab_cuts():
    """The cuts from the order statistics of coordinates split over ranks (here one) are
    `slab_cuts`' bit for bit, with repeated values and zeros of either sign."""
    from mpi4py import MPI

    from psph.decomposition.slabs import distributed_cuts

    rng = np.random.default_rng(3)
    for trial in range(60):
        n = int(rng.integers(1, 400))
        c = [rng.normal(size=n), np.round(rng.normal(size=n), 1),
             rng.integers(-3, 3, size=n) * 0.1][trial % 3] * 10.0 ** rng.integers(-3, 4)
        size, width = int(rng.integers(1, 8)), float(rng.choice([0.0, 0.05, 0.3]))
        got = distributed_cuts(c, size, width, MPI.COMM_SELF)
        want = slab_cuts(c, size, width)
        assert np.array_equal(got, want), (trial, got, want)
        assert got.tobytes() == want.tobytes() or 0.0 in want  # the sign of a zero cut

"""The scene's particle lattice without building it whole (issue 15, item 1).

Global order of the particles (their ids): each block's own lattice in row-major order
(x fastest), blocks in scene order, then the points of the domain lattice inside the
polygons, meshes and layers ("the fill"), in lattice order. `census` counts the particles
per coordinate along one axis (each rank evaluating a share of the fill's rows), from which
the slab cuts follow; `seed` builds only the particles of one slab [lo, hi) along an axis,
with their global ids. Both reach the other ranks through a `reducer` (element-wise
max / min / sum over ranks and the exclusive prefix sum over ranks, arrays as long as a
lattice's rows or columns): `SerialReducer` for one process, `psph.decomposition.slabs.
CommReducer` under MPI. Nothing here imports mpi4py.
"""

from __future__ import annotations

import numpy as np

from psph.scenes.geometry import inside_mesh, inside_polygon


class SerialReducer:
    """The reductions of a single process: every one is the identity."""

    rank = 0
    size = 1

    def max(self, a) -> np.ndarray:
        return np.array(a)

    def min(self, a) -> np.ndarray:
        return np.array(a)

    def sum(self, a) -> np.ndarray:
        return np.array(a)

    def exclusive_scan(self, a) -> np.ndarray:
        """Sum of the lower ranks' arrays (zeros on rank 0)."""
        return np.zeros_like(np.asarray(a))


SERIAL = SerialReducer()


def lattice_axes(lo, hi, dx: float) -> tuple[np.ndarray, np.ndarray]:
    """The x and y centres of `lattice_block(lo, hi, dx)` (the same floats)."""
    nx = max(int(round((hi[0] - lo[0]) / dx)), 1)
    ny = max(int(round((hi[1] - lo[1]) / dx)), 1)
    return lo[0] + (np.arange(nx) + 0.5) * dx, lo[1] + (np.arange(ny) + 0.5) * dx


def has_fill(scene) -> bool:
    pa = scene.particles
    return bool(pa.polygons or pa.meshes or pa.layers)


def fill_mask(scene, points: np.ndarray) -> np.ndarray:
    """Which domain-lattice points lie in a polygon, mesh or layer of the scene. Reads
    every file and checks every profile even for no points, so that bad input raises the
    same error on every rank."""
    from psph.scene import check_layer_profiles
    from psph.scenes.profiles import inside_layer

    pa = scene.particles
    taken = np.zeros(len(points), bool)
    for poly in pa.polygons:
        taken |= inside_polygon(points, poly.vertices)
    for mesh in pa.meshes:
        taken |= inside_mesh(points, mesh.file)
    for il, layer in enumerate(pa.layers):
        taken |= inside_layer(points, *check_layer_profiles(layer, f"particles.layers[{il}]"))
    return taken


def _grid(xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    gx, gy = np.meshgrid(xs, ys, indexing="xy")
    return np.column_stack([gx.ravel(), gy.ravel()])


def census(scene, axis: int, reducer=SERIAL) -> tuple[np.ndarray, np.ndarray]:
    """(values, counts): every particle coordinate along `axis` (values may repeat) and
    how many particles have it, the same on every rank (collective). Blocks are counted
    analytically; the fill's rows are shared among the ranks, each evaluating its own."""
    dx = scene.particles.dx
    values, counts = [], []
    for b in scene.particles.blocks:
        c = lattice_axes(b.min, b.max, dx)
        values.append(c[axis])
        counts.append(np.full(len(c[axis]), len(c[1 - axis]), np.int64))
    if has_fill(scene):
        xs, ys = lattice_axes(scene.domain.min, scene.domain.max, dx)
        r0 = reducer.rank * len(ys) // reducer.size
        r1 = (reducer.rank + 1) * len(ys) // reducer.size
        taken = fill_mask(scene, _grid(xs, ys[r0:r1])).reshape(r1 - r0, len(xs))
        if axis == 0:
            local = taken.sum(axis=0, dtype=np.int64)
        else:
            local = np.zeros(len(ys), np.int64)
            local[r0:r1] = taken.sum(axis=1, dtype=np.int64)
        values.append((xs, ys)[axis])
        counts.append(reducer.sum(local))
    return np.concatenate(values), np.concatenate(counts)


def _in_slab(c: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Indices of the (increasing) lattice coordinates c in [lo, hi)."""
    return np.flatnonzero((c >= lo) & (c < hi))


def seed(scene, axis: int = 0, lo: float = -np.inf, hi: float = np.inf,
         reducer=SERIAL) -> tuple[np.ndarray, np.ndarray]:
    """Positions (n, 2) and global ids (n,) int64 of the particles whose coordinate along
    `axis` lies in [lo, hi), in id order (collective: two reductions of the fill's per-row
    counts). The default slab is the whole scene on one process."""
    dx = scene.particles.dx
    xs_out, keys = [], []
    offset = 0
    for b in scene.particles.blocks:
        c = lattice_axes(b.min, b.max, dx)
        idx = [np.arange(len(c[0])), np.arange(len(c[1]))]
        idx[axis] = _in_slab(c[axis], lo, hi)
        xs_out.append(_grid(c[0][idx[0]], c[1][idx[1]]))
        keys.append((offset + idx[1][:, None] * len(c[0]) + idx[0][None, :]).ravel())
        offset += len(c[0]) * len(c[1])
    if has_fill(scene):
        xs, ys = lattice_axes(scene.domain.min, scene.domain.max, dx)
        idx = [np.arange(len(xs)), np.arange(len(ys))]
        idx[axis] = _in_slab((xs, ys)[axis], lo, hi)
        points = _grid(xs[idx[0]], ys[idx[1]])
        taken = fill_mask(scene, points).reshape(len(idx[1]), len(idx[0]))
        # id = offset + taken points in the rows below + in this row on lower ranks (the
        # slabs are in rank order along the axis) + those before it in this rank's row
        rows = np.zeros(len(ys), np.int64)
        rows[idx[1]] = taken.sum(axis=1, dtype=np.int64)
        per_row = reducer.sum(rows)
        lower = reducer.exclusive_scan(rows)
        first = offset + np.concatenate(([0], np.cumsum(per_row)[:-1])) + lower
        key = first[idx[1]][:, None] + np.cumsum(taken, axis=1, dtype=np.int64) - 1
        xs_out.append(points[taken.ravel()])
        keys.append(key[taken])
    return np.concatenate(xs_out), np.concatenate(keys)


def extent(x: np.ndarray, reducer=SERIAL) -> np.ndarray:
    """(2, dim): the smallest and the largest coordinate of all ranks' particles `x` along
    each axis (collective; exact, so the same bits as over one global array)."""
    dim = x.shape[1]
    lo = x.min(axis=0) if len(x) else np.full(dim, np.inf)
    hi = x.max(axis=0) if len(x) else np.full(dim, -np.inf)
    return np.stack([reducer.min(lo), reducer.max(hi)])


def nearest(points, x: np.ndarray, key: np.ndarray, reducer=SERIAL
            ) -> tuple[np.ndarray, np.ndarray]:
    """Global id (m,) and position (m, dim) of the particle nearest to each of the m
    `points` among all ranks' particles `x` with ids `key`; on a tie the lowest id, as the
    first argmin over all particles in id order (collective: three small reductions)."""
    points = np.asarray(points, float).reshape(len(points), -1)
    m, dim = points.shape
    d2 = [np.sum((x - pt) ** 2, axis=1) for pt in points]  # a few probes: a short loop
    best = reducer.min(np.array([d.min() if len(d) else np.inf for d in d2]))
    none = np.iinfo(np.int64).max
    ids = reducer.min(np.array([key[d == b].min() if np.any(d == b) else none
                                for d, b in zip(d2, best, strict=True)], np.int64))
    pos = np.full((m, dim), -np.inf)
    for j in range(m):
        hit = np.flatnonzero(key == ids[j])
        if len(hit):
            pos[j] = x[hit[0]]
    return ids, reducer.max(pos)

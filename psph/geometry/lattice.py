"""The scene's particle lattice without building it whole: each rank seeds only its own
slab, so that no rank holds the whole scene.

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

from psph.geometry.grids import check_layer_grids
from psph.geometry.profiles import check_layer_profiles, inside_layer
from psph.geometry.shapes import inside_polygon, inside_triangles, read_mesh
from psph.geometry.solids import inside_surface, read_surface


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


def lattice_axes(lo, hi, dx: float) -> tuple[np.ndarray, ...]:
    """The lattice centres along each axis of the box [lo, hi] (x, y and, in 3D, z)."""
    return tuple(lo[d] + (np.arange(max(int(round((hi[d] - lo[d]) / dx)), 1)) + 0.5) * dx
                 for d in range(len(lo)))


def _block_rows(c: tuple[np.ndarray, ...], idx: list[np.ndarray]) -> tuple[np.ndarray, ...]:
    """Positions (n, dim) and lattice indices (n,) of the block lattice points c[d][idx[d]]
    in the block's row-major order (x fastest, then y, then z)."""
    dim = len(c)
    rev = range(dim - 1, -1, -1)
    grids = np.meshgrid(*[c[d][idx[d]] for d in rev], indexing="ij")
    points = np.column_stack([grids[dim - 1 - d].ravel() for d in range(dim)])
    index = np.meshgrid(*[idx[d] for d in rev], indexing="ij")
    key = np.zeros(points.shape[0], np.int64)
    stride = 1
    for d in range(dim):
        key += index[dim - 1 - d].ravel() * stride
        stride *= len(c[d])
    return points, key


class Fill:
    """The polygons, meshes and layers of a scene, read once (every file and profile, so
    that bad input raises the same error on every rank), with the box that holds them."""

    def __init__(self, scene):
        pa = scene.particles
        self.polygons = [np.asarray(p.vertices, float) for p in pa.polygons]
        self.meshes = [read_mesh(m.file) for m in pa.meshes]
        self.layers = [check_layer_profiles(layer, f"particles.layers[{il}]")
                       for il, layer in enumerate(pa.layers)]
        # each source's material index, in the order polygons, meshes, layers
        self.indices = [material_index(scene, src.material)
                        for src in (*pa.polygons, *pa.meshes, *pa.layers)]
        corners = list(self.polygons) + [xy[tri.ravel()] for xy, tri in self.meshes]
        for top, bottom in self.layers:
            x0, x1 = max(top[0, 0], bottom[0, 0]), min(top[-1, 0], bottom[-1, 0])
            corners.append(np.array([[x0, bottom[:, 1].min()], [x1, top[:, 1].max()]]))
        self.empty = not corners
        if not self.empty:
            pts = np.concatenate(corners)
            # wider than any edge tolerance of the tests below (1e-9 of the shape's size)
            margin = 1e-6 * max(np.abs(pts).max(), 1.0) + 1e-9
            self.lo, self.hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin

    def span(self, c: np.ndarray, axis: int) -> np.ndarray:
        """Indices of the lattice coordinates c (along axis) within the box."""
        return np.flatnonzero((c >= self.lo[axis]) & (c <= self.hi[axis]))

    def mask(self, points: np.ndarray) -> np.ndarray:
        """Which points lie in a polygon, mesh or layer."""
        taken = np.zeros(len(points), bool)
        for vertices in self.polygons:
            taken |= inside_polygon(points, vertices)
        for xy, tri in self.meshes:
            taken |= inside_triangles(points, xy, tri)
        for top, bottom in self.layers:
            taken |= inside_layer(points, top, bottom)
        return taken

    def material(self, points: np.ndarray) -> np.ndarray:
        """The material index (float64) of points inside the fill: that of the last source
        (polygons, then meshes, then layers, each in scene order) that holds the point, as
        the fill takes a point once however many sources hold it. With one material every
        point gets 0 and no source is tested."""
        index = np.zeros(len(points))
        if not any(self.indices):
            return index
        tests = [lambda v=v: inside_polygon(points, v) for v in self.polygons]
        tests += [lambda m=m: inside_triangles(points, *m) for m in self.meshes]
        tests += [lambda lay=lay: inside_layer(points, *lay) for lay in self.layers]
        for test, k in zip(tests, self.indices, strict=True):
            index[test()] = k
        return index


class Fill3D:
    """The closed surface meshes (`particles.meshes`, read once), the spheres, the
    cylinders and the layers between elevation grids of a 3D scene, and the domain
    lattice points inside them
    (`solids.inside_surface`), in lattice order (x fastest, then y, then z). Every process
    evaluates the whole mask of their bounding box (a bool a lattice point: 10^7 points in
    10 MB)."""

    def __init__(self, scene):
        pa = scene.particles
        dx = scene.particles.dx
        self.surfaces = [read_surface(m.file, f"particles.meshes[{i}].file")
                         for i, m in enumerate(pa.meshes)]
        self.spheres = [(np.array(sp.centre, float), sp.radius) for sp in pa.spheres]
        self.cylinders = [(np.array(cy.base, float), cy.radius, cy.height)
                          for cy in pa.cylinders]
        axes = lattice_axes(scene.domain.min, scene.domain.max, dx)
        # soil between elevation grids, z at every lattice column
        self.layers = [check_layer_grids(layer, f"particles.layers[{il}]", axes[0], axes[1])
                       for il, layer in enumerate(pa.layers)]
        self.indices = [material_index(scene, m.material)
                        for m in (*pa.meshes, *pa.spheres, *pa.cylinders, *pa.layers)]
        self.empty = not (self.surfaces or self.spheres or self.cylinders or self.layers)
        if self.empty:
            return
        gy, gx = np.meshgrid(axes[1], axes[0], indexing="ij")
        layer_z = [(top.at(gx, gy), bottom.at(gx, gy)) for top, bottom in self.layers]
        xy = [axes[0][0], axes[0][-1], axes[1][0], axes[1][-1]]
        pts = np.concatenate([p for p, _ in self.surfaces]
                             + [np.stack([c - r, c + r]) for c, r in self.spheres]
                             + [np.stack([c - [r, r, 0], c + [r, r, h]])
                                for c, r, h in self.cylinders]
                             + [np.array([[xy[0], xy[2], zb.min()], [xy[1], xy[3], zt.max()]])
                                for zt, zb in layer_z])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        eps = 1e-9 * max(np.ptp(pts, axis=0).max(), 1.0)  # of the extent (UTM-sized x)
        self.idx = [np.flatnonzero((c >= lo[d] - eps) & (c <= hi[d] + eps))
                    for d, c in enumerate(axes)]
        self.axes = [c[i] for c, i in zip(axes, self.idx, strict=True)]
        masks = [inside_surface(*self.axes, p, t, dx) for p, t in self.surfaces]
        zz, yy, xx = np.meshgrid(self.axes[2], self.axes[1], self.axes[0], indexing="ij")
        masks += [(xx - c[0]) ** 2 + (yy - c[1]) ** 2 + (zz - c[2]) ** 2 <= r * r
                  for c, r in self.spheres]
        masks += [((xx - c[0]) ** 2 + (yy - c[1]) ** 2 <= r * r) & (zz >= c[2])
                  & (zz <= c[2] + h) for c, r, h in self.cylinders]
        cols = np.ix_(self.idx[1], self.idx[0])
        masks += [(zz >= zb[cols][None] - eps) & (zz <= zt[cols][None] + eps)
                  for zt, zb in layer_z]
        self.mask = np.logical_or.reduce(masks)
        self.material = np.zeros(self.mask.shape)
        for m, k in zip(masks, self.indices, strict=True):
            self.material[m] = k  # the last source that holds a point

    def points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(positions (n, 3), ordinal in the fill (n,), material (n,)) of every point."""
        kk, jj, ii = np.nonzero(self.mask)  # C order: x fastest
        xs, ys, zs = self.axes
        x = np.column_stack([xs[ii], ys[jj], zs[kk]])
        return x, np.arange(len(x), dtype=np.int64), self.material[kk, jj, ii]


def estimate_count(scene) -> float:
    """An estimate of the scene's particle count, from its sources' sizes only (no
    lattice is built, so it costs nothing at any dx): each block's lattice exactly; the
    fill (polygons, meshes, layers; in 3D spheres, cylinders and closed surfaces) as the
    volume of its sources over dx^dim: a polygon's area, a sphere's or a cylinder's volume
    times the share of its bounding box inside the domain (exact for the half, quarter or
    octant cut through its centre), a mesh's or a layer's bounding box within the domain,
    and the whole fill at most the box of all its sources within the domain. Overlapping
    sources are counted twice, a shape's rim to within the lattice's roughness."""
    dx = scene.particles.dx
    dim = scene.dim
    count = 0.0
    for b in scene.particles.blocks:
        count += float(np.prod([max(int(round((b.max[d] - b.min[d]) / dx)), 1)
                                for d in range(dim)]))
    dom_lo, dom_hi = np.array(scene.domain.min, float), np.array(scene.domain.max, float)

    def clipped(lo, hi) -> float:
        """Volume of the box [lo, hi] within the domain."""
        return float(np.prod(np.clip(np.minimum(hi, dom_hi) - np.maximum(lo, dom_lo), 0.0,
                                     None)))

    def inside(volume, lo, hi) -> float:
        """`volume` of a shape whose bounding box is [lo, hi], times the box's share in
        the domain."""
        box = float(np.prod(np.subtract(hi, lo)))
        return volume * clipped(lo, hi) / box if box > 0.0 else 0.0

    boxes, volumes = [], []  # each fill source's bounding box and volume estimate
    pa = scene.particles
    if dim == 2:
        fill = Fill(scene)
        for v in fill.polygons:
            area = 0.5 * abs(np.dot(v[:, 0], np.roll(v[:, 1], -1))
                             - np.dot(v[:, 1], np.roll(v[:, 0], -1)))
            boxes.append((v.min(axis=0), v.max(axis=0)))
            volumes.append(inside(area, *boxes[-1]))
        for xy, _ in fill.meshes:
            boxes.append((xy.min(axis=0), xy.max(axis=0)))
            volumes.append(clipped(*boxes[-1]))
        for top, bottom in fill.layers:
            pts = np.concatenate([top, bottom])
            boxes.append((pts.min(axis=0), pts.max(axis=0)))
            volumes.append(clipped(*boxes[-1]))
    else:
        from psph.geometry.shapes import mesh_triangles

        for i, m in enumerate(pa.meshes):
            pts = mesh_triangles(m.file, f"particles.meshes[{i}].file = {m.file!r}")[0]
            boxes.append((pts.min(axis=0), pts.max(axis=0)))
            volumes.append(clipped(*boxes[-1]))
        for sp in pa.spheres:
            c, r = np.array(sp.centre, float), sp.radius
            boxes.append((c - r, c + r))
            volumes.append(inside(4.0 / 3.0 * np.pi * r ** 3, *boxes[-1]))
        for cy in pa.cylinders:
            c, r, h = np.array(cy.base, float), cy.radius, cy.height
            boxes.append((c - [r, r, 0.0], c + [r, r, h]))
            volumes.append(inside(np.pi * r * r * h, *boxes[-1]))
        gx, gy = _columns(scene)  # layers between elevation grids: no lattice built
        for il, layer in enumerate(pa.layers):
            top, bottom = check_layer_grids(layer, f"particles.layers[{il}]",
                                            *lattice_axes(dom_lo, dom_hi, dx)[:2])
            zt = np.minimum(top.at(gx, gy), dom_hi[2])
            zb = np.maximum(bottom.at(gx, gy), dom_lo[2])
            boxes.append((np.array([dom_lo[0], dom_lo[1], zb.min()]),
                          np.array([dom_hi[0], dom_hi[1], zt.max()])))
            volumes.append(float(np.clip(zt - zb, 0.0, None).sum()) * dx * dx)
    if boxes:
        lo = np.min([b[0] for b in boxes], axis=0)
        hi = np.max([b[1] for b in boxes], axis=0)
        count += min(sum(volumes), clipped(lo, hi)) / dx ** dim
    return count


def occupancy(scene):
    """A test of which points (k, dim) hold soil: inside a block's box, or a domain
    lattice point of the fill (the polygons, meshes and layers; in 3D the closed
    surfaces' mask). For the exposed faces of a surface load (`physics.initial`)."""
    dx = scene.particles.dx
    boxes = [(np.array(b.min) - 1e-9, np.array(b.max) + 1e-9) for b in scene.particles.blocks]
    fill3 = Fill3D(scene) if scene.dim == 3 else None
    fill = Fill(scene) if scene.dim == 2 else None

    def occupied(points: np.ndarray) -> np.ndarray:
        taken = np.zeros(len(points), bool)
        for lo, hi in boxes:
            taken |= np.all((points >= lo) & (points <= hi), axis=1)
        if fill is not None and not fill.empty:
            taken |= fill.mask(points)
        if fill3 is not None and not fill3.empty:
            idx, ok = [], np.ones(len(points), bool)
            for d in range(3):
                c = fill3.axes[d]
                j = np.round((points[:, d] - c[0]) / dx).astype(np.int64) if len(c) else \
                    np.zeros(len(points), np.int64)
                ok &= (j >= 0) & (j < len(c))
                idx.append(np.clip(j, 0, max(len(c) - 1, 0)))
            hit = np.zeros(len(points), bool)
            hit[ok] = fill3.mask[idx[2][ok], idx[1][ok], idx[0][ok]]
            taken |= hit
        return taken

    return occupied


def _columns(scene) -> tuple[np.ndarray, np.ndarray]:
    """x and y of every lattice column of the domain (flat)."""
    c = lattice_axes(scene.domain.min, scene.domain.max, scene.particles.dx)
    gx, gy = np.meshgrid(c[0], c[1])
    return gx.ravel(), gy.ravel()


def material_index(scene, name: str | None) -> int:
    """Index of a source's `material` (None: 0, the first)."""
    if name is None:
        return 0
    return next(i for i, m in enumerate(scene.materials) if m.name == name)


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
        across = int(np.prod([len(c[d]) for d in range(len(c)) if d != axis]))
        counts.append(np.full(len(c[axis]), across, np.int64))
    if scene.dim == 3:
        fill3 = Fill3D(scene)
        if not fill3.empty:
            other = tuple(d for d in range(3) if d != axis)
            values.append(fill3.axes[axis])
            counts.append(fill3.mask.sum(axis=tuple(2 - d for d in other)).astype(np.int64))
        return np.concatenate(values), np.concatenate(counts)
    fill = Fill(scene)
    if not fill.empty:
        c = lattice_axes(scene.domain.min, scene.domain.max, dx)
        cols, rows = fill.span(c[0], 0), fill.span(c[1], 1)
        share = rows[reducer.rank * len(rows) // reducer.size:
                     (reducer.rank + 1) * len(rows) // reducer.size]
        taken = fill.mask(_grid(c[0][cols], c[1][share])).reshape(len(share), len(cols))
        local = np.zeros(len(c[axis]), np.int64)
        if axis == 0:
            local[cols] = taken.sum(axis=0, dtype=np.int64)
        else:
            local[share] = taken.sum(axis=1, dtype=np.int64)
        values.append(c[axis])
        counts.append(reducer.sum(local))
    return np.concatenate(values), np.concatenate(counts)


def _in_slab(c: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Indices of the (increasing) lattice coordinates c in [lo, hi)."""
    return np.flatnonzero((c >= lo) & (c < hi))


def seed(scene, axis: int = 0, lo: float = -np.inf, hi: float = np.inf,
         reducer=SERIAL, material: bool = False) -> tuple[np.ndarray, ...]:
    """Positions (n, dim) and global ids (n,) int64 of the particles whose coordinate along
    `axis` lies in [lo, hi), in id order (collective: two reductions of the fill's per-row
    counts). The default slab is the whole scene on one process. `material`: also each
    particle's material index (n,) float64, that of its source (`Fill.material`)."""
    dx = scene.particles.dx
    xs_out, keys, mats = [], [], []
    offset = 0
    for b in scene.particles.blocks:
        c = lattice_axes(b.min, b.max, dx)
        idx = [np.arange(len(cd)) for cd in c]
        idx[axis] = _in_slab(c[axis], lo, hi)
        points, key = _block_rows(c, idx)
        xs_out.append(points)
        keys.append(offset + key)
        mats.append(np.full(len(keys[-1]), float(material_index(scene, b.material))))
        offset += int(np.prod([len(cd) for cd in c]))
    if scene.dim == 3:
        fill3 = Fill3D(scene)
        if not fill3.empty:
            x3, k3, m3 = fill3.points()
            keep = (x3[:, axis] >= lo) & (x3[:, axis] < hi)
            xs_out.append(x3[keep])
            keys.append(offset + k3[keep])
            mats.append(m3[keep])
        fill = None
    else:
        fill = Fill(scene)
    if fill is not None and not fill.empty:
        xs, ys = lattice_axes(scene.domain.min, scene.domain.max, dx)
        idx = [fill.span(xs, 0), fill.span(ys, 1)]  # no point outside the box is taken
        c = (xs, ys)[axis][idx[axis]]
        idx[axis] = idx[axis][(c >= lo) & (c < hi)]
        points = _grid(xs[idx[0]], ys[idx[1]])
        taken = fill.mask(points).reshape(len(idx[1]), len(idx[0]))
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
        if material:
            mats.append(fill.material(xs_out[-1]))
    if material:
        return np.concatenate(xs_out), np.concatenate(keys), np.concatenate(mats)
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


def probe_ids(scene, x: np.ndarray | None = None, key: np.ndarray | None = None,
              reducer=SERIAL, slab: tuple | None = None) -> dict[str, tuple[int, tuple]]:
    """Global id and initial position of the particle nearest to each `output.probes`
    point, from each rank's initial particles `x` with ids `key` (default: seeded here for
    `slab`, or all of them on one process). Collective when any probe is set."""
    if not scene.output.probes:
        return {}
    if x is None:
        x, key = seed(scene, *(slab or ()), reducer=reducer)
    ids, pos = nearest(list(scene.output.probes.values()), x, key, reducer)
    return {name: (int(ids[j]), tuple(pos[j])) for j, name in enumerate(scene.output.probes)}

"""Particle generation from scene geometry: lattices, and which points lie inside."""

import numpy as np

from psph.errors import SceneError
from psph.geometry.columns import column_index, column_tops


def lattice_block(lo, hi, dx: float) -> np.ndarray:
    """Particles at the centres of a square lattice of spacing dx filling [lo, hi] (2D)."""
    nx = max(int(round((hi[0] - lo[0]) / dx)), 1)
    ny = max(int(round((hi[1] - lo[1]) / dx)), 1)
    xs = lo[0] + (np.arange(nx) + 0.5) * dx
    ys = lo[1] + (np.arange(ny) + 0.5) * dx
    gx, gy = np.meshgrid(xs, ys, indexing="xy")
    return np.column_stack([gx.ravel(), gy.ravel()])


def surface_layer(x: np.ndarray, side: str, dx: float, bounds: np.ndarray | None = None
                  ) -> np.ndarray:
    """Mask of the outermost particle layer on `side` (left, right, bottom, top; front,
    back in 3D, where bottom and top are along z). `bounds` (2, dim): the smallest and
    largest coordinates of all particles, when `x` holds only some of them (default:
    those of `x`)."""
    dim = x.shape[1]
    axis = 0 if side in ("left", "right") else 1 if side in ("front", "back") else dim - 1
    c = x[:, axis]
    if side in ("right", "back", "top"):
        return c > (c.max() if bounds is None else bounds[1, axis]) - 0.5 * dx
    return c < (c.min() if bounds is None else bounds[0, axis]) + 0.5 * dx


def domain_lattice(lo, hi, dx: float) -> np.ndarray:
    """Centres of the square lattice of spacing dx anchored at the domain's lower corner."""
    return lattice_block(lo, hi, dx)


def inside_polygon(points: np.ndarray, vertices) -> np.ndarray:
    """Mask of the points inside the polygon (even-odd rule, matplotlib's Path); points
    on an edge count as inside when the polygon is traced either way round."""
    from matplotlib.path import Path as MplPath

    path = MplPath(np.asarray(vertices, float))
    eps = 1e-9 * max(np.ptp(np.asarray(vertices, float), axis=0).max(), 1.0)
    return path.contains_points(points, radius=eps) | path.contains_points(points, radius=-eps)


def inside_mesh(points: np.ndarray, file: str) -> np.ndarray:
    """Mask of the points inside any triangle or quad of a mesh file (read by meshio)."""
    return inside_triangles(points, *read_mesh(file))


def read_mesh(file: str) -> tuple[np.ndarray, np.ndarray]:
    """(xy (k, 2), triangles (m, 3)) of a mesh file's triangles and quads (each quad as
    two triangles), read by meshio; SceneError (one line) if it cannot be used."""
    points, tri = mesh_triangles(file, f"particles.meshes: {file}")
    if not len(tri):
        raise SceneError(f"particles.meshes: {file}: no triangle or quad cells")
    return points[:, :2], tri


def mesh_triangles(file: str, where: str) -> tuple[np.ndarray, np.ndarray]:
    """(points (k, dim), triangles (m, 3), empty if none) of a mesh file's triangles and
    quads (each quad as two triangles), read by meshio; SceneError "<where>: meshio cannot
    read it (...)" (one line) if it cannot be read."""
    import contextlib
    import io

    import meshio

    try:  # meshio prints its own complaints and may exit: keep the one-line rule
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            mesh = meshio.read(file)
    except (Exception, SystemExit) as e:
        reason = (str(e).strip().splitlines() or [type(e).__name__])[0][:120]
        raise SceneError(f"{where}: meshio cannot read it ({reason})") from None
    tris = [np.zeros((0, 3), np.int64)]
    for block in mesh.cells:
        if block.type.startswith("triangle"):
            tris.append(block.data[:, :3])
        elif block.type.startswith("quad"):
            q = block.data[:, :4]
            tris += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
    return np.asarray(mesh.points, float), np.concatenate(tris).astype(np.int64)


def inside_triangles(points: np.ndarray, xy: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Mask of the points inside any of the triangles `tri` (vertex indices into xy)."""
    inside = np.zeros(len(points), bool)
    a, b, c = xy[tri[:, 0]], xy[tri[:, 1]], xy[tri[:, 2]]
    for k in range(len(tri)):  # per cell, only the lattice points in its bounding box
        lo = np.minimum(np.minimum(a[k], b[k]), c[k])
        hi = np.maximum(np.maximum(a[k], b[k]), c[k])
        sel = np.flatnonzero(np.all((points >= lo - 1e-12) & (points <= hi + 1e-12), axis=1))
        if not len(sel):
            continue
        p = points[sel]
        v0, v1, v2 = c[k] - a[k], b[k] - a[k], p - a[k]
        d00, d01, d11 = v0 @ v0, v0 @ v1, v1 @ v1
        d20, d21 = v2 @ v0, v2 @ v1
        den = d00 * d11 - d01 * d01
        if den == 0.0:
            continue
        u = (d11 * d20 - d01 * d21) / den
        w = (d00 * d21 - d01 * d20) / den
        tol = 1e-12
        inside[sel] |= (u >= -tol) & (w >= -tol) & (u + w <= 1 + tol)
    return inside


def removal_region(x: np.ndarray, region, dx: float, reducer) -> np.ndarray:
    """Mask of the points x (n, dim) inside a `[[remove]]` region (`schema.Removal`): a
    box (min, max); a polygon, in 2D in the x-y plane, in 3D in plan (x, y) with every
    point above it or, with `depth`, the points within `depth` of the highest point of
    their dx x dx column (a cut that follows the ground). Collective with `depth` (the
    columns' tops are a max over ranks, `reducer.max`)."""
    if region.polygon is None:
        return np.all((x >= np.array(region.min)) & (x <= np.array(region.max)), axis=1)
    inside = inside_polygon(x[:, :2], region.polygon)
    if x.shape[1] == 2 or region.depth is None:
        return inside
    lo = np.min(np.asarray(region.polygon, float), axis=0)
    span = np.ptp(np.asarray(region.polygon, float), axis=0)
    shape = tuple(int(n) for n in np.floor(span / dx).astype(np.int64) + 1)
    xin = x[inside]
    top = reducer.max(column_tops(xin, lo, dx, shape))
    deep = xin[:, 2] < top[column_index(xin, lo, dx, shape)] - region.depth
    inside[np.flatnonzero(inside)[deep]] = False
    return inside

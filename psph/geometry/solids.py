"""Soil volumes of 3D scenes from closed surface meshes: any surface meshio
reads (STL, OBJ, PLY, VTK, ...) made of triangles or quads, which must be closed (every
edge shared by exactly two faces); the points of the domain lattice inside it are soil.

Inside means an odd number of crossings of the upward vertical ray from the point with
the surface. The ray is offset from the lattice column by a fixed irrational fraction of
dx, so that it never passes exactly through an edge or a vertex of a mesh whose vertices
lie on the lattice (a crossing on an edge shared by two faces would count twice).
"""

import numpy as np

from psph.errors import SceneError
from psph.geometry.shapes import mesh_triangles

RAY_OFFSET = (0.5 ** 0.5 * 1e-4, 3 ** 0.5 * 1e-4)  # of dx, in x and y


def read_surface(file: str, key: str) -> tuple[np.ndarray, np.ndarray]:
    """(points (k, 3), triangles (m, 3)) of a closed surface mesh; SceneError with one
    line naming `key` if meshio cannot read it, it has no faces, or it is not closed."""
    points, tri = mesh_triangles(file, f"{key} = {file!r}")
    if not len(tri) or points.shape[1] != 3:
        raise SceneError(f"{key} = {file!r}: no triangle or quad faces in 3D (a surface "
                         "mesh closing the soil's volume is needed)")
    open_edges = _open_edges(tri)
    if open_edges:
        raise SceneError(f"{key} = {file!r}: the surface is not closed ({open_edges} edges "
                         "are not shared by exactly two faces); a volume needs a closed "
                         "surface")
    return points, tri


def _open_edges(tri: np.ndarray) -> int:
    """How many edges are not shared by exactly two triangles."""
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int(np.sum(counts != 2))


def inside_surface(xs: np.ndarray, ys: np.ndarray, zs: np.ndarray, points: np.ndarray,
                   tri: np.ndarray, dx: float) -> np.ndarray:
    """Mask (len(zs), len(ys), len(xs)) of the lattice points (xs[i], ys[j], zs[k]) inside
    the closed surface (points, tri), by the parity of the vertical ray's crossings."""
    nx, ny = len(xs), len(ys)
    ox, oy = RAY_OFFSET[0] * dx, RAY_OFFSET[1] * dx
    cols, heights = [], []
    a, b, c = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    for t in range(len(tri)):
        p, q, r = a[t], b[t], c[t]
        lo = np.minimum(np.minimum(p, q), r)
        hi = np.maximum(np.maximum(p, q), r)
        i0, i1 = np.searchsorted(xs + ox, [lo[0], hi[0]], side="left")
        j0, j1 = np.searchsorted(ys + oy, [lo[1], hi[1]], side="left")
        if i0 >= i1 or j0 >= j1:
            continue
        gx, gy = np.meshgrid(xs[i0:i1] + ox, ys[j0:j1] + oy, indexing="xy")
        gx, gy = gx.ravel(), gy.ravel()
        det = (q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1])
        if det == 0.0:  # a vertical face: the ray runs along it, no crossing
            continue
        u = ((gx - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (gy - p[1])) / det
        v = ((q[0] - p[0]) * (gy - p[1]) - (gx - p[0]) * (q[1] - p[1])) / det
        hit = (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0)
        if not hit.any():
            continue
        z = p[2] + u[hit] * (q[2] - p[2]) + v[hit] * (r[2] - p[2])
        jj, ii = np.divmod(np.flatnonzero(hit), i1 - i0)
        cols.append((j0 + jj) * nx + (i0 + ii))
        heights.append(z)
    mask = np.zeros((len(zs), ny, nx), bool)
    if not cols:
        return mask
    col = np.concatenate(cols)
    z = np.concatenate(heights)
    order = np.lexsort((z, col))
    col, z = col[order], z[order]
    # crossings above each lattice point of each column that has any
    for c in np.unique(col):
        zc = z[np.searchsorted(col, c):np.searchsorted(col, c, side="right")]
        above = len(zc) - np.searchsorted(zc, zs, side="right")
        j, i = divmod(int(c), nx)
        mask[:, j, i] = above % 2 == 1
    return mask

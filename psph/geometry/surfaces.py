"""Boundary particles of rigid surfaces in 3D: the 3D form of the polylines'
virtual particles (`polylines.py`), from a triangle surface (a mesh file meshio reads,
or vertices and triangles given inline).

The boundary particles are the points of the soil's own lattice (origin + (i + 1/2) dx,
as `polylines.lattice_particles` in 2D) on the surface's non-soil side within 2h of it:
as deep as the mirror ghosts of a plane wall, and a floor at a lattice plane gets its
first row exactly dx below the soil's lowest. Each records the nearest point of the
surface (its foot) and the unit normal there pointing into the soil: the face's normal
where the foot is inside a face (or on an edge between faces of one plane), the
direction from the particle to the foot where it is on an edge or a vertex. The soil
side of each face: "above" / "below" (the normal with positive / negative z: a surface
z(x, y), which must have no vertical face) or "outside" / "inside" of a closed,
consistently wound surface.

The nearest point of a triangle is Ericson's (Real-Time Collision Detection, 2005,
Sect. 5.1.5) by Voronoi regions. Where two faces are equally near (the foot on their
common edge) the one whose plane the point is farther from decides the side, so that a
point in the wedge of a ridge or a trough is put on its right side.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from psph.errors import SceneError

MAX_LATTICE_POINTS = 10_000_000  # the dense search box over a surface's bounds
# (about 50 bytes a point on every rank)


@nb.njit(cache=True)
def _closest_on_triangle(p0, p1, p2, a, b, c):
    """(foot, inside): the nearest point of triangle abc to p, and whether it is inside
    the face (not on an edge or a vertex)."""
    ab0, ab1, ab2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    ac0, ac1, ac2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    ap0, ap1, ap2 = p0 - a[0], p1 - a[1], p2 - a[2]
    d1 = ab0 * ap0 + ab1 * ap1 + ab2 * ap2
    d2 = ac0 * ap0 + ac1 * ap1 + ac2 * ap2
    if d1 <= 0.0 and d2 <= 0.0:
        return a[0], a[1], a[2], False
    bp0, bp1, bp2 = p0 - b[0], p1 - b[1], p2 - b[2]
    d3 = ab0 * bp0 + ab1 * bp1 + ab2 * bp2
    d4 = ac0 * bp0 + ac1 * bp1 + ac2 * bp2
    if d3 >= 0.0 and d4 <= d3:
        return b[0], b[1], b[2], False
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        return a[0] + t * ab0, a[1] + t * ab1, a[2] + t * ab2, False
    cp0, cp1, cp2 = p0 - c[0], p1 - c[1], p2 - c[2]
    d5 = ab0 * cp0 + ab1 * cp1 + ab2 * cp2
    d6 = ac0 * cp0 + ac1 * cp1 + ac2 * cp2
    if d6 >= 0.0 and d5 <= d6:
        return c[0], c[1], c[2], False
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        return a[0] + t * ac0, a[1] + t * ac1, a[2] + t * ac2, False
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return (b[0] + t * (c[0] - b[0]), b[1] + t * (c[1] - b[1]), b[2] + t * (c[2] - b[2]),
                False)
    den = 1.0 / (va + vb + vc)
    v = vb * den
    w = vc * den
    return (a[0] + ab0 * v + ac0 * w, a[1] + ab1 * v + ac1 * w, a[2] + ab2 * v + ac2 * w,
            True)


@nb.njit(cache=True)
def _nearest_faces(points, tri, normals, base, dx, counts, reach, best_d, best_side,
                   foot, face):
    """For every lattice point base + (i + 1/2) dx of the box `counts` within `reach` of
    a face: the nearest point of the surface (foot) and its face, its distance best_d
    and the signed distance best_side to the face's plane (normals point into the soil)."""
    tie = 1e-9 * dx
    nx, ny = counts[0], counts[1]
    for t in range(tri.shape[0]):
        a = points[tri[t, 0]]
        b = points[tri[t, 1]]
        c = points[tri[t, 2]]
        lo = np.empty(3, np.int64)
        hi = np.empty(3, np.int64)
        for d in range(3):
            mn = min(a[d], b[d], c[d]) - reach
            mx = max(a[d], b[d], c[d]) + reach
            lo[d] = max(int(math.ceil((mn - base[d]) / dx - 0.5)), 0)
            hi[d] = min(int(math.floor((mx - base[d]) / dx - 0.5)), counts[d] - 1)
        for k in range(lo[2], hi[2] + 1):
            p2 = base[2] + (k + 0.5) * dx
            for j in range(lo[1], hi[1] + 1):
                p1 = base[1] + (j + 0.5) * dx
                for i in range(lo[0], hi[0] + 1):
                    p0 = base[0] + (i + 0.5) * dx
                    f0, f1, f2, _ = _closest_on_triangle(p0, p1, p2, a, b, c)
                    e0, e1, e2 = p0 - f0, p1 - f1, p2 - f2
                    dist = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
                    if dist >= reach:
                        continue
                    side = e0 * normals[t, 0] + e1 * normals[t, 1] + e2 * normals[t, 2]
                    q = (k * ny + j) * nx + i
                    if dist < best_d[q] - tie or (dist <= best_d[q] + tie
                                                 and abs(side) > abs(best_side[q])):
                        best_d[q] = dist
                        best_side[q] = side
                        foot[q, 0], foot[q, 1], foot[q, 2] = f0, f1, f2
                        face[q] = t


def soil_normals(points: np.ndarray, tri: np.ndarray, soil: str, where: str) -> np.ndarray:
    """(m, 3) unit normals of the faces pointing to the soil side (module docstring);
    SceneError naming `where` for a degenerate face, a vertical face of a surface z(x, y),
    or an open or inconsistently wound surface with soil outside or inside."""
    e1 = points[tri[:, 1]] - points[tri[:, 0]]
    e2 = points[tri[:, 2]] - points[tri[:, 0]]
    cross = np.cross(e1, e2)
    area2 = np.linalg.norm(cross, axis=1)
    scale = max(float(np.ptp(points, axis=0).max()), 1e-300) ** 2
    if np.any(area2 <= 1e-12 * scale):
        f = int(np.argmax(area2 <= 1e-12 * scale))
        raise SceneError(f"{where}: face {f} has no area (a surface needs proper "
                         "triangles)")
    n = cross / area2[:, None]
    if soil in ("above", "below"):
        flat = np.abs(n[:, 2]) < 1e-9
        if flat.any():
            raise SceneError(f"{where}: face {int(np.argmax(flat))} is vertical; soil = "
                             f"'{soil}' needs a surface z(x, y) (a closed surface takes "
                             "soil = 'outside' or 'inside')")
        up = np.where(n[:, 2] > 0.0, 1.0, -1.0)
        return n * (up if soil == "above" else -up)[:, None]
    directed = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    _, counts = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    if np.any(counts != 2):
        raise SceneError(f"{where}: the surface is not closed ({int(np.sum(counts != 2))} "
                         f"edges are not shared by exactly two faces); soil = '{soil}' "
                         "needs a closed surface")
    if len(np.unique(directed, axis=0)) != len(directed):
        raise SceneError(f"{where}: the faces are not consistently wound (an edge runs "
                         f"the same way in two faces); soil = '{soil}' needs them so")
    volume = float(np.einsum("ij,ij->", points[tri[:, 0]], cross)) / 6.0
    outward = 1.0 if volume > 0.0 else -1.0
    return n * (outward if soil == "outside" else -outward)


def surface_particles(points: np.ndarray, tri: np.ndarray, soil: str, dx: float, h: float,
                      origin, lo, hi, where: str = "surface"
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, normal, foot), each (m, 3): the boundary particles of one surface within the
    box [lo, hi] (module docstring), in lattice order (x fastest, then y, z)."""
    normals = soil_normals(points, tri, soil, where)
    reach = 2.0 * h
    origin = np.asarray(origin, float)
    box_lo = np.maximum(points.min(axis=0) - reach, np.asarray(lo, float))
    box_hi = np.minimum(points.max(axis=0) + reach, np.asarray(hi, float))
    first = np.ceil((box_lo - origin) / dx - 0.5).astype(np.int64)
    last = np.floor((box_hi - origin) / dx - 0.5).astype(np.int64)
    counts = np.maximum(last - first + 1, 0)
    if int(np.prod(counts)) > MAX_LATTICE_POINTS:
        raise SceneError(f"{where}: its bounds hold {int(np.prod(counts))} lattice points "
                         f"at dx = {dx:g} (at most {MAX_LATTICE_POINTS}); a coarser dx or "
                         "a smaller surface")
    if not counts.all():
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3))
    base = origin + first * dx
    size = int(np.prod(counts))
    best_d = np.full(size, np.inf)
    best_side = np.zeros(size)
    foot = np.zeros((size, 3))
    face = np.full(size, -1, np.int64)
    _nearest_faces(np.ascontiguousarray(points, float), np.ascontiguousarray(tri, np.int64),
                   normals, base, dx, counts, reach, best_d, best_side, foot, face)
    keep = np.flatnonzero((best_d < reach) & (best_side < -1e-9 * dx))
    k, rest = np.divmod(keep, counts[0] * counts[1])
    j, i = np.divmod(rest, counts[0])
    x = base + (np.stack([i, j, k], axis=1) + 0.5) * dx
    f = foot[keep]
    radial = (f - x) / best_d[keep][:, None]
    flat = normals[face[keep]]  # the face's own normal wherever it is the direction
    on_face = np.einsum("ij,ij->i", radial, flat) > 1.0 - 1e-9
    return x, np.where(on_face[:, None], flat, radial), f

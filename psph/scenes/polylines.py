"""Boundary particles along polylines (issue 16): the virtual particles of the paper's
ref. [11] (Bui et al. 2008), several rows deep, fixed in space.

Each segment of a polyline carries rows k = 0, 1, ... at distances (k + 1/2) dx from the
line on its non-soil side, at arc lengths (i + 1/2) ds along it (ds = L / round(L / dx),
the nearest spacing to dx that fits the segment). Rows are deep enough to fill the kernel
support, (k + 1/2) dx < 2h, as the mirror ghosts of a plane wall reach 2h. A particle is
kept only where its nearest point of the polyline is on its own segment (the segment's
Voronoi strip), which trims the overlap of two segments' rows at a corner that opens
toward the soil; at a corner that opens toward the boundary side the gap between the two
segments' rows is filled with arcs of radius (k + 1/2) dx around the vertex. Every particle
records the unit normal pointing into the soil (the segment's, or the radial direction at
a vertex) and its foot, the nearest point of the line: the penetration check of
`kernels/boundary.py` tests a soil particle against the foot and normal of its nearest
boundary particle.
"""

from __future__ import annotations

import math

import numpy as np


def soil_normals(points: np.ndarray, soil: str) -> np.ndarray:
    """(k - 1, 2) unit normals of the segments, pointing to the soil side. The left
    normal (-t_z, t_x) of a segment t points up for a profile z(x) (x increasing) and to
    smaller x for a wall x(z) (z increasing)."""
    t = np.diff(points, axis=0)
    t /= np.linalg.norm(t, axis=1)[:, None]
    left = np.stack([-t[:, 1], t[:, 0]], axis=1)
    return left if soil in ("above", "left") else -left


def _nearest_on_polyline(q: np.ndarray, points: np.ndarray, segments: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each point of q: (segment index into `segments`, parameter in [0, 1],
    distance) of its nearest point on those segments of the polyline."""
    a = points[:-1][segments]
    d = (points[1:] - points[:-1])[segments]
    ll = (d * d).sum(axis=1)
    rel = q[:, None, :] - a[None, :, :]
    s = np.clip((rel * d[None]).sum(axis=2) / ll[None], 0.0, 1.0)
    foot = a[None] + s[..., None] * d[None]
    dist = np.linalg.norm(q[:, None, :] - foot, axis=2)
    seg = np.argmin(dist, axis=1)
    rows = np.arange(len(q))
    return seg, s[rows, seg], dist[rows, seg]


def boundary_particles(points: np.ndarray, soil: str, dx: float, h: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, normal, foot), each (m, 2): the boundary particles of one polyline (see the
    module docstring). Rows: (k + 1/2) dx < 2h."""
    nrows = int(math.ceil(2.0 * h / dx - 0.5))
    normals = soil_normals(points, soil)
    xs, ns, fs = [], [], []
    tol = 1e-9 * dx
    for j in range(len(points) - 1):
        a, b = points[j], points[j + 1]
        length = float(np.linalg.norm(b - a))
        m = max(1, int(round(length / dx)))
        s = (np.arange(m) + 0.5) / m
        foot = a[None] + s[:, None] * (b - a)[None]
        # only segments that come within the rows' reach of this one can be nearer
        reach = (nrows + 1) * dx
        lo, hi = np.minimum(a, b) - reach, np.maximum(a, b) + reach
        near = np.flatnonzero(np.all((np.maximum(points[:-1], points[1:]) >= lo)
                                     & (np.minimum(points[:-1], points[1:]) <= hi), axis=1))
        for k in range(nrows):
            q = foot - (k + 0.5) * dx * normals[j]
            # its own segment is at (k + 1/2) dx: drop it if another one is nearer
            keep = _nearest_on_polyline(q, points, near)[2] >= (k + 0.5) * dx - tol
            xs.append(q[keep])
            ns.append(np.repeat(normals[j][None], keep.sum(), axis=0))
            fs.append(foot[keep])
    for j in range(1, len(points) - 1):
        n0, n1 = normals[j - 1], normals[j]
        # a gap opens between the rows of segments j-1 and j (directions -n0, -n1 from
        # the vertex) when segment j turns away from the soil: t0 . n1 < 0
        t0 = points[j] - points[j - 1]
        a0 = math.atan2(-n0[1], -n0[0])
        a1 = math.atan2(-n1[1], -n1[0])
        sweep = (a1 - a0 + math.pi) % (2.0 * math.pi) - math.pi
        if np.dot(t0, n1) >= 0.0 or abs(sweep) < 1e-12:
            continue  # the corner opens toward the soil: the rows overlap, trimmed above
        for k in range(nrows):
            r = (k + 0.5) * dx
            m = max(1, int(round(abs(sweep) * r / dx)))
            ang = a0 + sweep * (np.arange(m) + 0.5) / m
            radial = np.stack([np.cos(ang), np.sin(ang)], axis=1)
            xs.append(points[j][None] + r * radial)
            ns.append(-radial)
            fs.append(np.repeat(points[j][None], m, axis=0))
    return np.concatenate(xs), np.concatenate(ns), np.concatenate(fs)

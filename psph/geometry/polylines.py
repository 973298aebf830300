"""Boundary particles along polylines: the virtual particles of the paper's
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
    # stations at an even spacing of about dx along the whole line, whatever its points'
    # spacing (a survey line sampled finer than dx gets no more particles)
    seg_len = np.linalg.norm(np.diff(points, axis=0), axis=1)
    cum = np.concatenate(([0.0], np.cumsum(seg_len)))
    m = max(1, int(round(cum[-1] / dx)))
    station = (np.arange(m) + 0.5) * (cum[-1] / m)
    on = np.clip(np.searchsorted(cum, station, side="right") - 1, 0, len(seg_len) - 1)
    for j in range(len(points) - 1):
        a, b = points[j], points[j + 1]
        s = (station[on == j] - cum[j]) / seg_len[j]
        if len(s) == 0:
            continue
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
            m = int(round(abs(sweep) * r / dx))
            if m == 0:  # a gap narrower than dx / 2: no particle
                continue
            ang = a0 + sweep * (np.arange(m) + 0.5) / m
            radial = np.stack([np.cos(ang), np.sin(ang)], axis=1)
            xs.append(points[j][None] + r * radial)
            ns.append(-radial)
            fs.append(np.repeat(points[j][None], m, axis=0))
    return np.concatenate(xs), np.concatenate(ns), np.concatenate(fs)


def _soil_start(line: np.ndarray, b0: float, dx: float, eps: float, sign: int) -> np.ndarray:
    """Per lattice column: the first soil row in the direction `sign` (+1: soil above, the
    lowest row j with b0 + (j + 1/2) dx >= line - eps, the rule of `inside_layer`; -1: soil
    below, minus the highest row with z <= line + eps), so that the soil rows are j' >= s."""
    if sign > 0:
        j = np.ceil((line - eps - b0) / dx - 0.5).astype(np.int64)
        z = lambda j: b0 + (j + 0.5) * dx  # noqa: E731  the lattice's floats
        j = np.where(z(j - 1) >= line - eps, j - 1, j)
        return np.where(z(j) < line - eps, j + 1, j)
    j = np.floor((line + eps - b0) / dx - 0.5).astype(np.int64)
    z = lambda j: b0 + (j + 0.5) * dx  # noqa: E731
    j = np.where(z(j + 1) <= line + eps, j + 1, j)
    return -np.where(z(j) > line + eps, j - 1, j)


def lattice_particles(points: np.ndarray, soil: str, dx: float, h: float, origin, lo, hi
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, normal, foot), each (m, 2): boundary particles of one polyline on the soil's own
    lattice (origin + (i + 1/2) dx, `lattice.lattice_axes`), for the columns within [lo,
    hi] and the line's range. Per column (along x for a profile, along z for a wall) the
    soil side starts at the first lattice row s_i on or beyond the line (`_soil_start`, the
    layer's rule bottom(x) <= z); the boundary particles are the rows j < s_i (counted away
    from the soil) within 2h of the soil of some column i' widened by dx/2 (where a plane
    wall would lie), (i - i')^2 + max(s_i' - 1/2 - j, 0)^2 < (2h/dx)^2: as deep as the
    mirror ghosts of a plane wall (3 rows for h = 1.3 dx). So the first boundary row is
    exactly dx from the soil's lowest row in every column, whatever the line's dip (the
    geometric rows of `boundary_particles` are (k + 1/2) dx below the line, dx/2 to 3dx/2
    from that row), and a steep column is filled down to its neighbours' rows. Normal and
    foot stay geometric: the nearest point of the line, with the segment's normal (the
    radial direction where it is an inner vertex)."""
    points = np.asarray(points, float)
    axis = 0 if soil in ("above", "below") else 1  # the line is a function of this axis
    up = 1 - axis
    sign = 1 if soil in ("above", "right") else -1
    eps = 1e-9 * max(np.ptp(points, axis=0).max(), 1.0)
    a0, b0 = float(origin[axis]), float(origin[up])
    i0 = int(math.ceil((max(points[0, axis], lo[axis]) - a0) / dx - 0.5))
    i1 = int(math.floor((min(points[-1, axis], hi[axis]) - a0) / dx - 0.5))
    cols = np.arange(i0, i1 + 1, dtype=np.int64)
    c = a0 + (cols + 0.5) * dx
    line = np.interp(c, points[:, axis], points[:, up])
    s = _soil_start(line, b0, dx, eps, sign)
    reach = int(math.ceil(2.0 * h / dx))
    q2 = (2.0 * h / dx) ** 2
    n = len(cols)
    pad = np.concatenate([np.full(reach, s.max()), s, np.full(reach, s.max())])
    deepest = np.min([pad[o:o + n] for o in range(2 * reach + 1)], axis=0) - reach
    depth = s - deepest  # rows deepest .. s - 1 of each column
    k = np.repeat(np.arange(n), depth)
    j = deepest[k] + np.arange(len(k)) - np.repeat(np.cumsum(depth) - depth, depth)
    keep = np.zeros(len(k), bool)
    for o in range(-reach, reach + 1):
        kk = k + o
        ok = (kk >= 0) & (kk < n)
        gap = np.maximum(s[np.clip(kk, 0, n - 1)] - j - 0.5, 0.0)
        keep |= ok & (o * o + gap * gap < q2)
    k, j = k[keep], j[keep]
    x = np.empty((len(k), 2))
    x[:, axis] = c[k]
    x[:, up] = b0 + (sign * j + 0.5) * dx
    normal, foot = _nearest_normals(x, points, soil, np.abs(x[:, up] - line[k]))
    return x, normal, foot


def _nearest_normals(x: np.ndarray, points: np.ndarray, soil: str, reach: np.ndarray,
                     chunk: int = 4096) -> tuple[np.ndarray, np.ndarray]:
    """(normal, foot) of points x on the boundary side: the nearest point of the polyline
    (no farther than `reach`, each point's distance to the line along its column) and the
    normal into the soil there: the segment's, or (x -> foot) at an inner vertex."""
    normals = soil_normals(points, soil)
    nseg = len(points) - 1
    normal, foot = np.empty_like(x), np.empty_like(x)
    seg_lo = np.minimum(points[:-1], points[1:])
    seg_hi = np.maximum(points[:-1], points[1:])
    for a in range(0, len(x), chunk):
        q = x[a:a + chunk]
        r = reach[a:a + chunk].max() + 1e-9
        near = np.flatnonzero(np.all((seg_hi >= q.min(axis=0) - r)
                                     & (seg_lo <= q.max(axis=0) + r), axis=1))
        seg, t, dist = _nearest_on_polyline(q, points, near)
        seg = near[seg]
        f = points[seg] + t[:, None] * (points[seg + 1] - points[seg])
        nrm = normals[seg].copy()
        vertex = (((t <= 0.0) & (seg > 0)) | ((t >= 1.0) & (seg < nseg - 1))) & (dist > 0.0)
        nrm[vertex] = (f[vertex] - q[vertex]) / dist[vertex, None]
        normal[a:a + chunk], foot[a:a + chunk] = nrm, f
    return normal, foot

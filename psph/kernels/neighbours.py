"""Cell-linked lists with particles sorted by cell, and id order inside a cell.

Cells are squares of side >= 2h on a grid anchored at a global origin, so a cell's integer
coordinates are the same on every rank. Cells are numbered row-major (y, then x): the local
numbering is the restriction of the global one, and with particles in key order inside a
cell every particle sees its neighbours in the same order on any number of ranks. That is
what makes 1-rank and N-rank runs bitwise identical.
"""

import numba as nb
import numpy as np


@nb.njit(cache=True, inline="always")
def half_stencil(k, c, sa, cx, cy, ncx, ncy, cell_start):
    """Neighbour cell k (0-4) of the half stencil around cell c = (cx, cy) and the first
    sorted slot to visit in it, or (-1, 0) outside the grid. k = 0: the rest of cell c
    after slot sa; then (+1, 0), (-1, +1), (0, +1), (+1, +1). Visiting these from every
    cell meets each pair once, in an order fixed by the global cell numbering."""
    if k == 0:
        return c, sa + 1
    if k == 1:
        ox, oy = 1, 0
    elif k == 2:
        ox, oy = -1, 1
    elif k == 3:
        ox, oy = 0, 1
    else:
        ox, oy = 1, 1
    nx = cx + ox
    ny = cy + oy
    if nx < 0 or nx >= ncx or ny >= ncy:
        return -1, 0
    nc = ny * ncx + nx
    return nc, cell_start[nc]


@nb.njit(cache=True, inline="always")
def _clamped_cell(c, origin, cell_size, lo, hi):
    """Cell coordinate of c, clamped to [lo, hi]; NaN goes to lo. Particles outside the
    domain are flagged by the update (exit 3); clamping keeps the grid bounded meanwhile."""
    f = (c - origin) / cell_size
    if not f >= lo:
        return lo
    if f >= hi:
        return hi
    return int(np.floor(f))


@nb.njit(cache=True)
def bin_particles(x, key, n, origin, cell_size, lo, ncell, cell_of, cell_start, fill, order):
    """Counting sort of particles 0..n-1 into cells, then insertion sort by key in a cell.

    x: (cap, 2) positions; key: (cap,) global sort keys; origin: (2,) global grid origin;
    lo: (2,) int64 lowest local cell coordinates; ncell: (2,) int64 local grid size.
    Outputs (preallocated): cell_of (cap,), cell_start (>= ncx*ncy + 1,), fill (>= ncx*ncy,)
    scratch, order (cap,).
    Particles outside the local grid (only possible after one left the domain, which the
    update reports as a failure) are clamped into its edge cells.
    """
    ncx = ncell[0]
    ncy = ncell[1]
    nc = ncx * ncy
    for c in range(nc + 1):
        cell_start[c] = 0
    for i in range(n):
        cx = _clamped_cell(x[i, 0], origin[0], cell_size, lo[0], lo[0] + ncx - 1) - lo[0]
        cy = _clamped_cell(x[i, 1], origin[1], cell_size, lo[1], lo[1] + ncy - 1) - lo[1]
        c = cy * ncx + cx
        cell_of[i] = c
        cell_start[c + 1] += 1
    for c in range(nc):
        cell_start[c + 1] += cell_start[c]
    # stable scatter, then order each cell by key (cells hold a handful of particles)
    for c in range(nc):
        fill[c] = cell_start[c]
    for i in range(n):
        c = cell_of[i]
        order[fill[c]] = i
        fill[c] += 1
    for c in range(nc):
        s = cell_start[c]
        e = cell_start[c + 1]
        for a in range(s + 1, e):
            p = order[a]
            kp = key[p]
            b = a - 1
            while b >= s and key[order[b]] > kp:
                order[b + 1] = order[b]
                b -= 1
            order[b + 1] = p


@nb.njit(cache=True)
def grid_bounds(x, n, origin, cell_size, cmax, lo, ncell):
    """Lowest cell coordinates `lo` and grid size `ncell` covering particles 0..n-1, with a
    one-cell margin, cell coordinates limited to [0, cmax] (the domain's grid)."""
    if n == 0:
        lo[0] = 0
        lo[1] = 0
        ncell[0] = 1
        ncell[1] = 1
        return
    c0min = c1min = 1 << 62
    c0max = c1max = -(1 << 62)
    for i in range(n):
        c0 = _clamped_cell(x[i, 0], origin[0], cell_size, 1, cmax[0] - 1)
        c1 = _clamped_cell(x[i, 1], origin[1], cell_size, 1, cmax[1] - 1)
        c0min = min(c0min, c0)
        c0max = max(c0max, c0)
        c1min = min(c1min, c1)
        c1max = max(c1max, c1)
    lo[0] = c0min - 1
    lo[1] = c1min - 1
    ncell[0] = c0max - c0min + 3
    ncell[1] = c1max - c1min + 3


def cell_lists(x: np.ndarray, h: float,
               key: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(cell_start, order, ncell) of a whole particle set in one go, cells of side 2h
    (the pair sweeps' layout); for verification drivers and tests, not the time loop,
    which keeps its arrays. key: the sort key within a cell (default: the index)."""
    return cell_lists_indexed(x, h, key)[1:]


def cell_lists_indexed(x: np.ndarray, h: float, key: np.ndarray | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(cell_of, cell_start, order, ncell): `cell_lists` with each particle's cell."""
    n = len(x)
    key = np.arange(n, dtype=float) if key is None else key
    cs = 2 * h
    origin = x.min(axis=0) - 4 * cs
    lo = np.zeros(2, np.int64)
    ncell = np.zeros(2, np.int64)
    grid_bounds(x, n, origin, cs, np.array([1 << 40, 1 << 40], np.int64), lo, ncell)
    nc = int(ncell.prod())
    cell_of = np.zeros(n, np.int64)
    cell_start = np.zeros(nc + 1, np.int64)
    order = np.zeros(n, np.int64)
    bin_particles(x, key, n, origin, cs, lo, ncell, cell_of, cell_start,
                  np.zeros(nc + 1, np.int64), order)
    return cell_of, cell_start, order, ncell

"""Cell-linked lists with particles sorted by cell, and id order inside a cell, in 2D and 3D.

Cells are squares (cubes) of side >= 2h / span on a grid anchored at a global origin (span 1
for the cell-list kernels; the pair sweep's grid, `pair_cell_span`, has cells of side h in
3D), so a cell's integer coordinates are the same on every rank. Cells are numbered
row-major (z, then y, then x): the local numbering is the restriction of the global one, and
with particles in key order inside a cell every particle sees its neighbours in the same
order on any number of ranks. That is what makes 1-rank and N-rank runs bitwise identical.
The dimension is that of the positions (x.shape[1]); a 2D grid is a 3D grid one cell
thick, so 2D keeps its cell numbers and its stencil order.
"""

import numba as nb
import numpy as np

# the half stencil of a cell on cells of side 2h / span: the cells after it in the
# row-major order (z, y, x) among the (2 span + 1)^dim - 1 around it, as offsets (ox, oy, oz):
# (+1..+span, 0, 0); (-span..+span, +1..+span, 0); in 3D (-span..+span, -span..+span,
# +1..+span), x fastest. `forward_slots` visits them as runs of consecutive sorted slots.


@nb.njit(cache=True, inline="always")
def next_cell(cx, cy, cz, ncx, ncy):
    """The cell after (cx, cy, cz) in the global row-major order, x fastest (a sweep over
    cells c = 0, 1, ... starts from (-1, 0, 0)).

    Parameters
    ----------
    cx, cy, cz : int
        the cell's coordinates on the local grid.
    ncx, ncy : int
        the grid's size along x and y.

    Returns
    -------
    cx, cy, cz : int
        the next cell's coordinates.
    """
    cx += 1
    if cx == ncx:
        cx = 0
        cy += 1
        if cy == ncy:
            cy = 0
            cz += 1
    return cx, cy, cz


def pair_cell_span(dim: int) -> int:
    """Cells of the pair sweep's grid across the 2h support: its cells have side 2h / span.

    2D: 1 (side 2h). 3D: 2 (side h): on a lattice at h = 1.2 dx a particle's half stencil
    then visits 93 candidates instead of 157 for the same 26 pairs, and the 3D sweep
    takes 15 % less time.
    The other cell-list kernels (Shepard, the boundary particles, non-local softening)
    keep cells of side 2h.

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    int
        span.
    """
    return 1 if dim == 2 else 2


@nb.njit(cache=True, inline="always")
def half_stencil_rows(dim: int, span: int = 1) -> int:
    """The number of slot runs of `forward_slots` to visit.

    Parameters
    ----------
    dim : int
        2 or 3.
    span : int
        cells across 2h (`pair_cell_span`).

    Returns
    -------
    int
        1 + span in 2D, 1 + span + span (2 span + 1) in 3D (2 and 5 at span 1, 13 in 3D
        at span 2).
    """
    return 1 + span if dim == 2 else 1 + span + span * (2 * span + 1)


@nb.njit(cache=True, inline="always")
def forward_slots(r, c, sa, cx, cy, cz, ncx, ncy, ncz, cell_start, dim, span=1):
    """The r-th run of sorted slots (s0, s1) of the half stencil of slot sa in cell
    c = (cx, cy, cz), or (0, 0) outside the grid, on a grid of cells of side 2h / span
    (`pair_cell_span`). Cells are numbered x fastest, so the half stencil's cells that
    share a row are consecutive, and so are their slots: r = 0 is the rest of cell c and
    cells (+1..+span, 0, 0); r = 1..span the rows (-span..+span, r, 0); in 3D the next
    ones the rows (-span..+span, -span..+span, +1..+span), y fastest: the half stencil's
    cells (the comment above) in the global cell order, with one bounds check per row
    instead of one per cell (tests/test_kernels_3d.py checks the runs against the
    offsets).

    Parameters
    ----------
    r : int
        the run, 0 <= r < `half_stencil_rows(dim, span)`.
    c : int
        the cell's index.
    sa : int
        the particle's slot in the cell list.
    cx, cy, cz : int
        the cell's coordinates.
    ncx, ncy, ncz : int
        the grid's size (ncz = 1 in 2D).
    cell_start : int64 array
        the cell list's slot offsets per cell.
    dim : int
        2 or 3.
    span : int
        cells across 2h.

    Returns
    -------
    s0, s1 : int
        the run of slots [s0, s1).
    """
    xlo = cx - span if cx >= span else 0
    xhi = cx + span if cx < ncx - span else ncx - 1
    if r == 0:
        return sa + 1, cell_start[c + 1 + xhi - cx]
    if r <= span or dim == 2:
        ny, nz = cy + r, cz
    else:
        k = r - span - 1
        ny, nz = cy + k % (2 * span + 1) - span, cz + 1 + k // (2 * span + 1)
    if ny < 0 or ny >= ncy or nz >= ncz:
        return 0, 0
    row = (nz * ncy + ny) * ncx
    return cell_start[row + xlo], cell_start[row + xhi + 1]


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
def gather_sorted(x, order, n, out):
    """out[s] = x[order[s]] for slots s < n: positions in the cell list's slot order.

    Parameters
    ----------
    x : (cap, dim) float64 array
        positions (m).
    order : (cap,) int64 array
        the cell list's rows in slot order.
    n : int
        number of slots.
    out : (>= n, dim) float64 array
        receives the sorted positions (m).
    """
    for s in range(n):
        o = order[s]
        for d in range(x.shape[1]):
            out[s, d] = x[o, d]


@nb.njit(cache=True)
def count_owned(order, n, n_owned, out):
    """out[s] = how many of slots 0..s-1 hold owned rows, s <= n: a run of slots [s0, s1)
    holds an owned row iff out[s1] > out[s0].

    Parameters
    ----------
    order : (cap,) int64 array
        the cell list's rows in slot order.
    n : int
        number of slots.
    n_owned : int
        rows below it are owned.
    out : (>= n + 1,) int64 array
        receives the counts.
    """
    out[0] = 0
    for s in range(n):
        out[s + 1] = out[s] + (1 if order[s] < n_owned else 0)


@nb.njit(cache=True)
def bin_particles(x, key, n, origin, cell_size, lo, ncell, cell_of, cell_start, fill, order):
    """Counting sort of particles 0..n-1 into cells, then insertion sort by key in a cell.

    Particles outside the local grid (only possible after one left the domain, which the
    update reports as a failure) are clamped into its edge cells.

    Parameters
    ----------
    x : (cap, dim) float64 array
        positions (m).
    key : (cap,) float64 array
        global sort keys (the particles' ids).
    n : int
        number of particles.
    origin : (dim,) float64 array
        the global grid's origin (m).
    cell_size : float
        cell side (m).
    lo : (dim,) int64 array
        lowest local cell coordinates (`grid_bounds`).
    ncell : (dim,) int64 array
        local grid size.
    cell_of : (cap,) int64 array
        receives each particle's cell.
    cell_start : (>= prod(ncell) + 1,) int64 array
        receives each cell's first slot.
    fill : (>= prod(ncell),) int64 array
        scratch.
    order : (cap,) int64 array
        receives the rows in slot order.
    """
    three = x.shape[1] == 3
    ncx = ncell[0]
    ncy = ncell[1]
    ncz = ncell[2] if three else 1
    nc = ncx * ncy * ncz
    for c in range(nc + 1):
        cell_start[c] = 0
    for i in range(n):
        cx = _clamped_cell(x[i, 0], origin[0], cell_size, lo[0], lo[0] + ncx - 1) - lo[0]
        cy = _clamped_cell(x[i, 1], origin[1], cell_size, lo[1], lo[1] + ncy - 1) - lo[1]
        c = cy * ncx + cx
        if three:
            cz = _clamped_cell(x[i, 2], origin[2], cell_size, lo[2], lo[2] + ncz - 1) - lo[2]
            c += cz * ncx * ncy
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
    """The local grid covering particles 0..n-1, with a one-cell margin.

    Parameters
    ----------
    x : (cap, dim) float64 array
        positions (m).
    n : int
        number of particles.
    origin : (dim,) float64 array
        the global grid's origin (m).
    cell_size : float
        cell side (m).
    cmax : (dim,) int64 array
        the domain grid's size: cell coordinates are limited to [0, cmax].
    lo : (dim,) int64 array
        receives the lowest cell coordinates.
    ncell : (dim,) int64 array
        receives the grid size.
    """
    three = x.shape[1] == 3
    if n == 0:
        for d in range(x.shape[1]):
            lo[d] = 0
            ncell[d] = 1
        return
    c0min = c1min = c2min = 1 << 62
    c0max = c1max = c2max = -(1 << 62)
    for i in range(n):
        c0 = _clamped_cell(x[i, 0], origin[0], cell_size, 1, cmax[0] - 1)
        c1 = _clamped_cell(x[i, 1], origin[1], cell_size, 1, cmax[1] - 1)
        c0min = min(c0min, c0)
        c0max = max(c0max, c0)
        c1min = min(c1min, c1)
        c1max = max(c1max, c1)
        if three:
            c2 = _clamped_cell(x[i, 2], origin[2], cell_size, 1, cmax[2] - 1)
            c2min = min(c2min, c2)
            c2max = max(c2max, c2)
    lo[0] = c0min - 1
    lo[1] = c1min - 1
    ncell[0] = c0max - c0min + 3
    ncell[1] = c1max - c1min + 3
    if three:
        lo[2] = c2min - 1
        ncell[2] = c2max - c2min + 3


@nb.njit(cache=True)
def neighbour_pairs(n, x, h, cell_start, order, ncell, pairs, span=1):
    """The pairs (a, b) of particles 0..n-1 closer than 2h, each once, in the half-stencil
    order of the pair sweeps (2D or 3D, by x.shape[1]).

    Parameters
    ----------
    n : int
        number of particles.
    x : (cap, dim) float64 array
        positions (m).
    h : float
        smoothing length (m).
    cell_start, order, ncell : int64 arrays
        a cell list with cells of side 2h / span.
    pairs : (m, 2) int64 array
        receives the pairs.
    span : int
        cells across 2h (the sweep's: `pair_cell_span`).

    Returns
    -------
    int
        the number of pairs, or -1 if m rows are not enough.
    """
    dim = x.shape[1]
    ncx = ncell[0]
    ncy = ncell[1]
    ncz = ncell[2] if dim == 3 else 1
    n_rows = half_stencil_rows(dim, span)
    reach2 = 4.0 * h * h
    m = 0
    cx, cy, cz = -1, 0, 0
    for c in range(ncx * ncy * ncz):
        cx, cy, cz = next_cell(cx, cy, cz, ncx, ncy)
        for sa in range(cell_start[c], cell_start[c + 1]):
            a = order[sa]
            if a >= n:
                continue
            for row in range(n_rows):
                s0, s1 = forward_slots(row, c, sa, cx, cy, cz, ncx, ncy, ncz, cell_start, dim,
                                       span)
                for s in range(s0, s1):
                    b = order[s]
                    if b >= n:
                        continue
                    r2 = 0.0
                    for d in range(dim):
                        e = x[b, d] - x[a, d]
                        r2 += e * e
                    if r2 >= reach2:
                        continue
                    if m >= pairs.shape[0]:
                        return -1
                    pairs[m, 0] = a
                    pairs[m, 1] = b
                    m += 1
    return m


def cell_lists(x: np.ndarray, h: float, key: np.ndarray | None = None,
               span: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cell list of a whole particle set (2D or 3D) in one go, for verification drivers
    and tests (the time loop keeps its own arrays).

    Parameters
    ----------
    x : (n, dim) float64 array
        positions (m).
    h : float
        smoothing length (m).
    key : (n,) float64 array, optional
        the sort key within a cell (default: the index).
    span : int
        cells across 2h: 1 for the cell-list kernels' layout (`pair_cell_lists` for the
        pair sweep's).

    Returns
    -------
    cell_start, order, ncell : int64 arrays
    """
    return cell_lists_indexed(x, h, key, span)[1:]


def pair_cell_lists(x: np.ndarray, h: float, key: np.ndarray | None = None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`cell_lists` in the pair sweep's layout (`pair_cell_span`: cells of side h in 3D).

    Parameters
    ----------
    x, h, key
        as `cell_lists`.

    Returns
    -------
    cell_start, order, ncell : int64 arrays
    """
    return cell_lists(x, h, key, pair_cell_span(x.shape[1]))


def cell_lists_indexed(x: np.ndarray, h: float, key: np.ndarray | None = None,
                       span: int = 1
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`cell_lists` with each particle's cell.

    Parameters
    ----------
    x, h, key, span
        as `cell_lists`.

    Returns
    -------
    cell_of, cell_start, order, ncell : int64 arrays
    """
    n, dim = x.shape
    key = np.arange(n, dtype=float) if key is None else key
    cs = 2 * h / span
    origin = x.min(axis=0) - 4 * cs
    lo = np.zeros(dim, np.int64)
    ncell = np.zeros(dim, np.int64)
    grid_bounds(x, n, origin, cs, np.full(dim, 1 << 40, np.int64), lo, ncell)
    nc = int(ncell.prod())
    cell_of = np.zeros(n, np.int64)
    cell_start = np.zeros(nc + 1, np.int64)
    order = np.zeros(n, np.int64)
    bin_particles(x, key, n, origin, cs, lo, ncell, cell_of, cell_start,
                  np.zeros(nc + 1, np.int64), order)
    return cell_of, cell_start, order, ncell

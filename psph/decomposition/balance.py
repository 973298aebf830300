"""Slab cuts from the particle distribution, computed in parallel.

Each cut is found by bisection on the coordinate: one small Allreduce of the counts below
the trial cuts per iteration, so no rank ever holds all coordinates. Inner slabs are kept
at least `min_width` wide, since a halo only reaches the next rank.
"""

import numpy as np
from mpi4py import MPI


def balanced_cuts(comm, coord: np.ndarray, min_width: float, iterations: int = 60,
                  parts: int | None = None) -> np.ndarray:
    """Cuts (parts + 1,) so that each of `parts` slabs (default: one a rank) holds about
    the same number of particles.

    coord: this rank's particle coordinates along the slab axis. Collective.
    The outer cuts are -inf and +inf.
    """
    size = comm.Get_size() if parts is None else parts
    cuts = np.full(size + 1, np.inf)
    cuts[0] = -np.inf
    if size == 1:
        return cuts
    c = np.sort(coord)
    n_total = comm.allreduce(len(c), op=MPI.SUM)
    if n_total == 0:  # nothing to cut (an empty slab of boxes): the first part takes all
        return cuts
    lo = comm.allreduce(float(c[0]) if len(c) else np.inf, op=MPI.MIN)
    hi = comm.allreduce(float(c[-1]) if len(c) else -np.inf, op=MPI.MAX)
    target = np.array([r * n_total // size for r in range(1, size)], np.int64)
    a = np.full(size - 1, lo)
    b = np.full(size - 1, np.nextafter(hi, np.inf))
    local = np.zeros(size - 1, np.int64)
    below = np.zeros(size - 1, np.int64)
    for _ in range(iterations):
        mid = 0.5 * (a + b)
        local[:] = np.searchsorted(c, mid, side="left")
        comm.Allreduce(local, below, op=MPI.SUM)
        few = below < target
        a = np.where(few, mid, a)
        b = np.where(few, b, mid)
        if np.all(b - a <= 1e-12 * max(1.0, abs(hi), abs(lo))):
            break
    # put each cut midway between the particles on either side of it, so that particles
    # on a lattice row do not sit on the cut
    idx = np.searchsorted(c, b, side="left")
    below_max = np.where(idx > 0, c[np.maximum(idx - 1, 0)], -np.inf) if len(c) else \
        np.full(size - 1, -np.inf)
    above_min = np.where(idx < len(c), c[np.minimum(idx, len(c) - 1)], np.inf) if len(c) \
        else np.full(size - 1, np.inf)
    below_max = _allreduce(comm, below_max, MPI.MAX)
    above_min = _allreduce(comm, above_min, MPI.MIN)
    inner = np.where(np.isfinite(below_max) & np.isfinite(above_min),
                     0.5 * (below_max + above_min), b)
    for r in range(1, size - 1):  # slab r spans inner[r-1]..inner[r]
        inner[r] = max(inner[r], inner[r - 1] + min_width)
    cuts[1:size] = inner
    return cuts



def _allreduce(comm, a: np.ndarray, op) -> np.ndarray:
    a = np.ascontiguousarray(a, float)
    out = np.empty_like(a)
    comm.Allreduce(a, out, op=op)
    return out

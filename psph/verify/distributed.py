"""Snapshot metrics over the ranks without a global array (so that no rank holds a whole
snapshot, whatever the particle count): each rank reads its share of a snapshot's rows,
order statistics come from the slab cuts' bisection of counts (`order_statistics`),
extremes from one small gather, and a neighbour sum from the rows of a slab of x with a
halo.

Every function is collective over `comm` (an mpi4py communicator; `MPI.COMM_SELF` for one
process, where the results are those of the serial numpy expressions bit for bit:
`percentiles` is `np.percentile`'s default "linear" method)."""

from __future__ import annotations

import h5py
import numpy as np
from mpi4py import MPI

from psph.decomposition.slabs import distributed_cuts, order_statistics
from psph.kernels.exact_sum import EXPANSION_CAP, dot_expansion, exact_total, local_parts


def share(n: int, comm) -> tuple[int, int]:
    """Rows lo..hi of n that this rank reads (contiguous, in rank order)."""
    r, p = comm.Get_rank(), comm.Get_size()
    return r * n // p, (r + 1) * n // p


def read_share(group: h5py.Group, names, comm) -> dict[str, np.ndarray]:
    """This rank's `share` of the rows of the datasets `names` of one snapshot group."""
    lo, hi = share(len(group["id"]), comm)
    return {k: group[k][lo:hi] for k in names}


def percentiles(values: np.ndarray, qs, comm) -> list[float]:
    """`np.percentile(all values, qs)` (method "linear") from the order statistics."""
    n = comm.allreduce(len(values))
    quantiles = np.true_divide(np.asarray(qs, float), 100)
    virtual = (n - 1) * quantiles
    below = np.floor(virtual).astype(np.int64)
    above = np.minimum(below + 1, n - 1)
    stats = order_statistics(np.asarray(values, float), np.concatenate([below, above]),
                             comm)
    a, b = np.array(stats[:len(qs)]), np.array(stats[len(qs):])
    gamma = virtual - below
    diff = b - a  # numpy's _lerp: from the nearer end
    return [float(v) for v in np.where(gamma >= 0.5, b - diff * (1 - gamma), a + diff * gamma)]


def exact_dot(a: np.ndarray, b: np.ndarray, comm) -> float:
    """sum_k a_k b_k over all ranks' rows, correctly rounded: the same bits on any
    partition (the ranks' exact expansions gathered, psph/kernels/exact_sum.py)."""
    a = np.ascontiguousarray(a, float)
    b = np.ascontiguousarray(b, float)
    partials = np.zeros(EXPANSION_CAP)
    parts = local_parts(partials, dot_expansion(a, b, len(a), partials)).copy()
    return exact_total(comm.allgather(parts))


def extreme(values: np.ndarray, ids: np.ndarray, x: np.ndarray, comm, largest: bool
            ) -> tuple[float, int, list[float]]:
    """(value, id, position) of the smallest (or largest) value over all ranks; a tie goes
    to the lowest id."""
    if len(values):
        v = values.max() if largest else values.min()
        j = int(np.flatnonzero(values == v)[np.argmin(ids[values == v])])
        mine = (float(-v if largest else v), int(ids[j]), [float(c) for c in x[j]])
    else:
        mine = (np.inf, np.iinfo(np.int64).max, [])
    best = min(comm.allgather(mine), key=lambda t: (t[0], t[1]))
    return (-best[0] if largest else best[0]), best[1], best[2]


def with_halo(x: np.ndarray, fields: dict[str, np.ndarray], reach: float, comm
              ) -> tuple[np.ndarray, dict[str, np.ndarray], int]:
    """The rows of a slab of x (cuts by `distributed_cuts`, slabs at least `reach` wide)
    first, then copies of the other slabs' rows within `reach` of its faces: (x, fields,
    the number of owned rows). Rows keep their order within each source rank."""
    size = comm.Get_size()
    if size == 1:
        return x, fields, len(x)
    cuts = distributed_cuts(x[:, 0].copy(), size, reach, comm)
    owner = np.clip(np.searchsorted(cuts[1:-1], x[:, 0], side="right"), 0, size - 1)
    left = (owner > 0) & (x[:, 0] < cuts[owner] + reach)
    right = (owner < size - 1) & (x[:, 0] >= cuts[owner + 1] - reach)
    names = list(fields)
    cols = [x] + [fields[k].reshape(len(x), int(np.prod(fields[k].shape[1:]))) for k in names]
    widths = [c.shape[1] for c in cols]
    table = np.hstack(cols + [np.zeros((len(x), 1))])  # last column: 1 on a halo copy
    dest = np.concatenate([owner, owner[left] - 1, owner[right] + 1])
    rows = np.concatenate([np.arange(len(x)), np.flatnonzero(left), np.flatnonzero(right)])
    halo = np.concatenate([np.zeros(len(x)), np.ones(left.sum() + right.sum())])
    order = np.lexsort((halo, dest))
    send = table[rows[order]]
    send[:, -1] = halo[order]
    w = send.shape[1]
    send_counts = np.bincount(dest, minlength=size).astype(np.int64)
    recv_counts = np.zeros(size, np.int64)
    comm.Alltoall(send_counts, recv_counts)
    recv = np.zeros((max(int(recv_counts.sum()), 1), w))
    sd = np.concatenate(([0], np.cumsum(send_counts)[:-1])) * w
    rd = np.concatenate(([0], np.cumsum(recv_counts)[:-1])) * w
    comm.Alltoallv([np.ascontiguousarray(send), (send_counts * w, sd), MPI.DOUBLE],
                   [recv, (recv_counts * w, rd), MPI.DOUBLE])
    recv = recv[:int(recv_counts.sum())]
    recv = recv[np.argsort(recv[:, -1], kind="stable")]  # owned rows first
    n_owned = int(np.sum(recv[:, -1] == 0.0))
    at = np.cumsum([0] + widths)
    out = {k: recv[:, at[j + 1]:at[j + 2]].reshape((len(recv),) + fields[k].shape[1:])
           for j, k in enumerate(names)}
    return recv[:, :2].copy(), out, n_owned

"""The particle census without global arrays: every id 0..n_ids-1 is either owned by
exactly one rank or removed (by a `remove` region) exactly once.

At each snapshot the owned ids are checked against the expected count and two
order-independent checksums (the sum of the ids and the sum of a 64-bit hash of them,
both modulo 2**64): one small reduction, no array of n_ids anywhere. The expected values
start from the checksums of the full range 0..n_ids-1 (each rank hashes its share of the
range) and lose those of the removed particles as they go. Each rank keeps the ids it
removed (its share of them), so that when a check fails a second pass, a bincount spread
over the ranks by id range, names the first id owned by the wrong number of ranks.
"""

import numpy as np
from mpi4py import MPI

from psph.errors import NumericalError

CHUNK = 1 << 20  # ids hashed at a time
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


def id_hash(ids: np.ndarray) -> np.ndarray:
    """splitmix64 of each id (uint64; wraps modulo 2**64)."""
    z = np.asarray(ids).astype(np.uint64) + _GOLDEN
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


def checksums(ids: np.ndarray) -> np.ndarray:
    """[count, sum of ids, sum of id_hash(ids)] as uint64, sums modulo 2**64; the same for
    any order or split of `ids` (the parts' checksums add)."""
    out = np.zeros(3, np.uint64)
    for a in range(0, len(ids), CHUNK):
        part = np.asarray(ids[a:a + CHUNK])
        out[0] += np.uint64(len(part))
        out[1] += part.astype(np.uint64).sum(dtype=np.uint64)
        out[2] += id_hash(part).sum(dtype=np.uint64)
    return out


def range_checksums(lo: int, hi: int) -> np.ndarray:
    """`checksums(np.arange(lo, hi))`, built a chunk at a time."""
    out = np.zeros(3, np.uint64)
    for a in range(lo, hi, CHUNK):
        out += checksums(np.arange(a, min(a + CHUNK, hi), dtype=np.int64))
    return out


def _share(n: int, rank: int, size: int) -> tuple[int, int]:
    return rank * n // size, (rank + 1) * n // size


def _allreduce_sum(comm, a: np.ndarray) -> np.ndarray:
    out = np.empty_like(a)
    comm.Allreduce(np.ascontiguousarray(a), out, op=MPI.SUM)
    return out


def _to_owner(comm, values: np.ndarray, dest: np.ndarray) -> np.ndarray:
    """Every rank's `values` sent to rank `dest` of each (collective); this rank's."""
    size = comm.Get_size()
    order = np.argsort(dest, kind="stable")
    send = np.ascontiguousarray(values[order], np.int64)
    send_counts = np.bincount(dest, minlength=size).astype(np.int64)
    recv_counts = np.zeros(size, np.int64)
    comm.Alltoall(send_counts, recv_counts)
    recv = np.zeros(max(int(recv_counts.sum()), 1), np.int64)
    sd = np.concatenate(([0], np.cumsum(send_counts)[:-1]))
    rd = np.concatenate(([0], np.cumsum(recv_counts)[:-1]))
    comm.Alltoallv([send if len(send) else np.zeros(1, np.int64), (send_counts, sd),
                    MPI.INT64_T], [recv, (recv_counts, rd), MPI.INT64_T])
    return recv[:int(recv_counts.sum())]


class Census:
    """The expected ids of one run on this rank: `n_ids` ids ever created, this rank's
    share `removed` of the ids removed so far, and the expected global checksums of the
    owned ids (the same on every rank)."""

    def __init__(self, comm, n_ids: int, removed: np.ndarray | None = None):
        """Collective: hashes this rank's share of 0..n_ids-1 and its `removed` ids."""
        self.comm = comm
        self.n_ids = int(n_ids)
        self.removed = np.zeros(0, np.int64) if removed is None \
            else np.asarray(removed, np.int64)
        lo, hi = _share(self.n_ids, comm.Get_rank(), comm.Get_size())
        local = np.stack([range_checksums(lo, hi), checksums(self.removed)])
        total = _allreduce_sum(comm, local)
        self.expected = total[0] - total[1]  # wraps modulo 2**64, as the sums do

    @property
    def n_alive(self) -> int:
        """The particles still in the run (all ranks)."""
        return int(self.expected[0])

    def remove(self, ids: np.ndarray) -> int:
        """This rank removed its owned particles `ids` (collective: every rank calls it at
        the same removal). Returns how many were removed on all ranks."""
        ids = np.asarray(ids, np.int64)
        self.removed = np.concatenate([self.removed, ids])
        gone = _allreduce_sum(self.comm, checksums(ids))
        self.expected = self.expected - gone
        return int(gone[0])

    def check(self, keys: np.ndarray, step: int, t: float) -> None:
        """The owned `keys` of every rank are the expected ids, each once (collective);
        raises NumericalError naming the first id lost or duplicated."""
        ids = np.asarray(keys).astype(np.int64)
        stray = (ids < 0) | (ids >= self.n_ids)
        local = np.append(checksums(ids), np.uint64(np.count_nonzero(stray)))
        total = _allreduce_sum(self.comm, local)
        if total[3] == 0 and np.array_equal(total[:3], self.expected):
            return
        self._report(ids, stray, int(total[3]), step, t)

    def _report(self, ids: np.ndarray, stray: np.ndarray, n_stray: int, step: int,
                t: float) -> None:
        """The second pass, only after a failed check: the owned and the removed ids go to
        the rank holding their id range, which counts them (collective)."""
        comm, size = self.comm, self.comm.Get_size()
        lo, hi = _share(self.n_ids, comm.Get_rank(), size)
        ids = ids[~stray]

        starts = np.arange(size, dtype=np.int64) * self.n_ids // size

        def owner(a):  # the rank whose share of 0..n_ids-1 holds each id
            return np.searchsorted(starts, a, side="right") - 1

        owned = np.bincount(_to_owner(comm, ids, owner(ids)) - lo, minlength=hi - lo)
        gone = self.removed[(self.removed >= 0) & (self.removed < self.n_ids)]
        removed = np.bincount(_to_owner(comm, gone, owner(gone)) - lo, minlength=hi - lo)
        bad = np.flatnonzero(owned + removed != 1)
        first = (lo + int(bad[0]), int(owned[bad[0]]), max(1 - int(removed[bad[0]]), 0)) \
            if len(bad) else None
        found = [f for f in comm.allgather(first) if f is not None]
        n_bad = comm.allreduce(len(bad), op=MPI.SUM)
        pid, count, expected = min(found) if found else (-1, 0, 1)
        raise NumericalError(
            f"step {step}, t = {t:.6g} s, particle id {pid}: field id (owned by {count} "
            f"ranks instead of {expected}; {n_bad} ids wrong, {n_stray} unknown ids) - "
            "particles lost or duplicated in migration")

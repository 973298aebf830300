"""Slabs along one axis, one per rank: halo exchange and migration every step, load
balancing (recut + redistribute) when the work gets uneven. The particle census is in
census.py.

Each rank owns the particles whose coordinate along `axis` lies in [lo, hi). Every step,
`exchange` sends to each neighbour rank in one message the particles that left the slab
(migrants, full state) and the owned particles within `width` of the cut (halo, full
state), and receives the same. A rank also keeps copies of its own migrants as halo for
that step, since its neighbour packed its halo before knowing of them.
"""


import numpy as np
from mpi4py import MPI

from psph.decomposition.balance import balanced_cuts
from psph.kernels.exact_sum import exact_total
from psph.kernels.packing import compact_rows, pack_rows, select_slab_rows, unpack_rows
from psph.state.particles import ParticleStore

# parts of an expansion that `exact_sum` gathers in one fixed-size row (the chunk
# accumulators of `psph.kernels.exact_sum` give at most 67; most sums need a handful)
_SUM_SLOTS = 72


def slab_cuts(coords: np.ndarray, nranks: int, min_width: float = 0.0) -> np.ndarray:
    """Cut positions (nranks + 1,) giving each rank about the same number of particles,
    inner slabs at least `min_width` wide (a halo reaches one rank only); the outer cuts
    are -inf and +inf. `coords`: all particles (the same array on every rank)."""
    cuts = np.full(nranks + 1, np.inf)
    cuts[0] = -np.inf
    if nranks > 1:
        c = np.sort(coords)
        n = len(c)
        for r in range(1, nranks):
            k = min(max(r * n // nranks, 1), n - 1)
            cuts[r] = 0.5 * (c[k - 1] + c[k])
        for r in range(2, nranks):
            cuts[r] = max(cuts[r], cuts[r - 1] + min_width)
    return cuts


def cuts_from_counts(values: np.ndarray, counts: np.ndarray, nranks: int,
                     min_width: float = 0.0) -> np.ndarray:
    """`slab_cuts` of the coordinates given as a histogram: `counts[i]` particles at
    `values[i]` (values may repeat, counts may be 0). The same cuts, bit for bit, as
    `slab_cuts` of the expanded array, from arrays as long as the lattice's columns."""
    cuts = np.full(nranks + 1, np.inf)
    cuts[0] = -np.inf
    if nranks > 1:
        order = np.argsort(values, kind="stable")
        v = np.asarray(values, float)[order]
        end = np.cumsum(np.asarray(counts, np.int64)[order])  # sorted index after each value
        n = int(end[-1])

        def at(k: int) -> float:  # c[k] of the sorted expanded coordinates
            return v[np.searchsorted(end, k % n, side="right")]

        for r in range(1, nranks):
            k = min(max(r * n // nranks, 1), n - 1)
            cuts[r] = 0.5 * (at(k - 1) + at(k))
        for r in range(2, nranks):
            cuts[r] = max(cuts[r], cuts[r - 1] + min_width)
    return cuts


def _ordered_keys(values: np.ndarray) -> np.ndarray:
    """int64 keys ordered as the float64 `values` (no NaN): the sign bit flips the rest;
    -0.0 counts as 0.0 (np.sort leaves their order open: a cut there may then differ from
    `slab_cuts`' in the sign of zero only, which owns the same particles)."""
    bits = (np.asarray(values, np.float64) + 0.0).view(np.int64)
    return np.where(bits < 0, bits ^ np.int64(0x7FFFFFFFFFFFFFFF), bits)


def _key_value(keys: np.ndarray) -> np.ndarray:
    bits = np.where(keys < 0, keys ^ np.int64(0x7FFFFFFFFFFFFFFF), keys)
    return bits.astype(np.int64).view(np.float64)


def order_statistics(coords: np.ndarray, ks: np.ndarray, comm) -> np.ndarray:
    """c[ks] of the sorted concatenation c of every rank's `coords` (exact; collective):
    a bisection on the float bits, each step one reduction of len(ks) counts."""
    keys = np.sort(_ordered_keys(coords))
    ks = np.asarray(ks, np.int64)
    big = np.iinfo(np.int64)
    first = comm.allreduce(int(keys[0]) if len(keys) else big.max, op=MPI.MIN)
    last = comm.allreduce(int(keys[-1]) if len(keys) else big.min, op=MPI.MAX)
    lo = np.full(len(ks), first, np.int64)
    hi = np.full(len(ks), last, np.int64)  # the answer lies in [lo, hi] (every rank's)
    while np.any(lo < hi):
        mid = (lo >> 1) + (hi >> 1) + (lo & hi & 1)  # no overflow
        below = np.searchsorted(keys, mid, side="right").astype(np.int64)
        comm.Allreduce(below.copy(), below, op=MPI.SUM)
        enough = below > ks  # at least k + 1 values <= mid: c[k] <= mid
        hi = np.where(enough, mid, hi)
        lo = np.where(enough, lo, mid + 1)
    return _key_value(lo)


def distributed_cuts(coords: np.ndarray, nranks: int, min_width: float, comm
                     ) -> np.ndarray:
    """`slab_cuts` of every rank's `coords` together, bit for bit, without gathering
    them (collective on `comm`, cutting for `nranks`): the few order statistics the cuts
    read are found by `order_statistics`, then `cuts_from_counts` runs on a histogram in
    which each particle counts at the next of them in sorted order (the values between
    are never read)."""
    n = int(comm.allreduce(len(coords), op=MPI.SUM))
    if nranks == 1:
        return slab_cuts(np.zeros(0), 1, min_width)
    ks = np.array([min(max(r * n // nranks, 1), n - 1) for r in range(1, nranks)])
    ks = np.unique(np.concatenate([(ks - 1) % n, ks % n]))
    values = order_statistics(coords, ks, comm)
    counts = np.diff(np.concatenate(([-1], ks)))
    counts[-1] += n - 1 - ks[-1]
    return cuts_from_counts(values, counts, nranks, min_width)


class CommReducer:
    """The reductions of psph/geometry/lattice.py over the ranks of `comm` (each a
    collective on a small array)."""

    def __init__(self, comm):
        self.comm = comm
        self.rank = comm.Get_rank()
        self.size = comm.Get_size()

    def _all(self, a, op) -> np.ndarray:
        a = np.ascontiguousarray(a)
        out = np.empty_like(a)
        self.comm.Allreduce(a, out, op=op)
        return out

    def max(self, a) -> np.ndarray:
        return self._all(a, MPI.MAX)

    def min(self, a) -> np.ndarray:
        return self._all(a, MPI.MIN)

    def sum(self, a) -> np.ndarray:
        return self._all(a, MPI.SUM)

    def exclusive_scan(self, a) -> np.ndarray:
        """Sum of the lower ranks' arrays (zeros on rank 0)."""
        a = np.ascontiguousarray(a)
        out = np.zeros_like(a)
        self.comm.Exscan(a, out, op=MPI.SUM)
        if self.rank == 0:  # MPI leaves rank 0's result undefined
            out[...] = 0
        return out


class Slabs:
    """Owns the communicator and the slab layout; the only place particles cross ranks."""

    def __init__(self, axis: int, cuts: np.ndarray, comm=None):
        self.comm = MPI.COMM_WORLD if comm is None else comm
        self.rank = self.comm.Get_rank()
        self.size = self.comm.Get_size()
        self.axis = axis
        self.set_cuts(cuts)
        self.reducer = CommReducer(self.comm)
        self.rebalances = 0
        self.last_imbalance = 1.0
        self.max_imbalance = 1.0  # the largest the rebalance check has seen
        self.max_after_recut = 1.0  # the largest right after a recut
        self.down = self.rank - 1 if self.rank > 0 else MPI.PROC_NULL
        self.up = self.rank + 1 if self.rank < self.size - 1 else MPI.PROC_NULL
        self._idx_cap = 0
        self._send = {}
        self._recv = {}
        self._row_map = np.zeros(0, np.int64)
        self._refresh_plan = {}
        self._refresh_one_plan = None  # `_refresh_one`'s, built from the plan when used

    # --------------------------------------------------------------- setup

    def set_cuts(self, cuts: np.ndarray) -> None:
        self.cuts = np.asarray(cuts, float).copy()
        self.lo = self.cuts[self.rank]
        self.hi = self.cuts[self.rank + 1]

    @property
    def slab(self) -> tuple[int, float, float]:
        """(axis, lo, hi): this rank owns the coordinates along axis in [lo, hi)."""
        return self.axis, float(self.lo), float(self.hi)

    @property
    def region(self) -> tuple[tuple[int, float, float], ...]:
        """This rank's part of the domain as (axis, lo, hi) along each cut axis."""
        return (self.slab,)

    def describe(self) -> dict:
        """The layout for summary.json."""
        return {"layout": "slabs", "axis": int(self.axis),
                "cuts": [float(c) for c in self.cuts[1:-1]]}

    def settle(self, store: ParticleStore) -> None:
        """Freshly seeded particles (in `slab`) to their owners: they are there already."""

    def owned_mask(self, x: np.ndarray) -> np.ndarray:
        c = x[:, self.axis]
        return (c >= self.lo) & (c < self.hi)

    # --------------------------------------------------------------- per step

    def _index_buffers(self, n: int) -> None:
        if n > self._idx_cap:
            cap = max(n, int(1.5 * self._idx_cap), 64)
            self._idx = {k: np.zeros(cap, np.int64)
                         for k in ("md", "mu", "hd", "hu", "keep")}
            self._idx_cap = cap

    def _send_buffer(self, name: str, rows: int, width: int) -> np.ndarray:
        # one buffer per name and width: fields of different widths refreshed in turn
        # must not regrow a shared one every call
        buf = self._send.get((name, width))
        if buf is None or buf.shape[0] < rows:
            buf = np.zeros((max(rows, 2 * (buf.shape[0] if buf is not None else 16)), width))
            self._send[(name, width)] = buf
        return buf

    def exchange(self, store: ParticleStore, width: float) -> None:
        """Migrate particles that left the slab and refill the halo (rows after owned)."""
        store.n_halo = store.n_ghost = 0
        if self.size == 1:
            return
        n = store.n_owned
        self._index_buffers(n)
        ix = self._idx
        coord = store.x[:n, self.axis]
        nmd, nmu, nhd, nhu, nk = select_slab_rows(
            coord, n, self.lo, self.hi, width, self.down == MPI.PROC_NULL,
            self.up == MPI.PROC_NULL, ix["md"], ix["mu"], ix["hd"], ix["hu"], ix["keep"])
        w = store.row_width
        # message: header row [n_migrants, n_halo, ...] then migrant rows, then halo rows
        bufs = {}
        for name, nm, nh, mi, hi_ in (("down", nmd, nhd, ix["md"], ix["hd"]),
                                      ("up", nmu, nhu, ix["mu"], ix["hu"])):
            buf = self._send_buffer(name, 1 + nm + nh, w)
            buf[0, 0] = nm
            buf[0, 1] = nh
            pack_rows(store.all_rows, mi, nm, buf[1:1 + nm])
            pack_rows(store.all_rows, hi_, nh, buf[1 + nm:1 + nm + nh])
            bufs[name] = buf[:1 + nm + nh]
        # own migrants stay as halo copies this step
        own = self._send_buffer("own", nmd + nmu, w)
        pack_rows(store.all_rows, ix["md"], nmd, own[:nmd])
        pack_rows(store.all_rows, ix["mu"], nmu, own[nmd:nmd + nmu])
        n_own_migr = nmd + nmu
        if n_own_migr:
            compact_rows(store.all_rows, ix["keep"], nk)
        store.n_owned = nk
        # halo rows sent, as row indices after the compaction (for refresh_halo)
        if n_own_migr:
            new_row = self._new_row(n)
            new_row[ix["keep"][:nk]] = np.arange(nk)
            self._halo_sent = (new_row[ix["hd"][:nhd]], new_row[ix["hu"][:nhu]])
        else:
            self._halo_sent = (ix["hd"][:nhd].copy(), ix["hu"][:nhu].copy())
        migrants_in = {}
        halo_in = {}

        reqs = [self.comm.Isend(bufs["up"], dest=self.up, tag=11),
                self.comm.Isend(bufs["down"], dest=self.down, tag=12)]
        received = []
        for source, tag in ((self.down, 11), (self.up, 12)):
            if source == MPI.PROC_NULL:
                continue
            status = MPI.Status()
            self.comm.Probe(source=source, tag=tag, status=status)
            rows = status.Get_count(MPI.DOUBLE) // w
            rbuf = self._recv.get(tag)
            if rbuf is None or rbuf.shape[0] < rows or rbuf.shape[1] != w:
                rbuf = np.zeros((max(rows, 64, 2 * (0 if rbuf is None else rbuf.shape[0])), w))
                self._recv[tag] = rbuf
            rbuf = rbuf[:rows]
            self.comm.Recv(rbuf, source=source, tag=tag)
            nm, nh = int(rbuf[0, 0]), int(rbuf[0, 1])
            # migrants become owned right away; halo rows are appended after all owned
            store.ensure(store.n_owned + nm + 64)
            unpack_rows(rbuf[1:1 + nm], nm, store.all_rows, store.n_owned)
            migrants_in[source] = (store.n_owned, nm)
            halo_in[source] = nh
            store.n_owned += nm
            received.append(rbuf[1 + nm:1 + nm + nh])
        MPI.Request.Waitall(reqs)
        start = store.n_owned
        total_halo = sum(len(r) for r in received) + n_own_migr
        store.ensure(start + total_halo + 64)
        for r in received:
            unpack_rows(r, len(r), store.all_rows, start)
            start += len(r)
        if n_own_migr:
            unpack_rows(own, n_own_migr, store.all_rows, start)
            start += n_own_migr
        store.n_halo = start - store.n_owned
        # where each neighbour's fresh values go in refresh_halo: its halo rows, then the
        # copies of the particles this rank just handed it
        first = store.n_owned
        nh_down = halo_in.get(self.down, 0)
        nh_up = halo_in.get(self.up, 0)
        own_at = first + nh_down + nh_up
        self._refresh_one_plan = None
        self._refresh_plan = {
            self.down: (self._halo_sent[0], migrants_in.get(self.down, (0, 0)),
                        (first, nh_down), (own_at, nmd)),
            self.up: (self._halo_sent[1], migrants_in.get(self.up, (0, 0)),
                      (first + nh_down, nh_up), (own_at + nmd, nmu)),
        }

    def _new_row(self, n: int) -> np.ndarray:
        if self._row_map.shape[0] < n:
            self._row_map = np.zeros(max(n, 2 * self._row_map.shape[0]), np.int64)
        return self._row_map

    def refresh_halo(self, *fields: np.ndarray) -> None:
        """Overwrite the halo rows of each field ((cap,) or (cap, k)) with the owners'
        current values, for the same halo as the last `exchange` (no particle has moved
        since): one message per neighbour for all the fields. Each neighbour sends its
        halo rows for this rank, then its current rows of the particles this rank handed
        it in that exchange."""
        if self.size == 1:
            return
        if len(fields) == 1 and (fields[0].ndim == 1 or fields[0].shape[1] == 1):
            self._refresh_one(fields[0].reshape(-1))  # (cap,) or (cap, 1): a view either way
            return
        cols = [f if f.ndim == 2 else f[:, None] for f in fields]  # views, never copies
        widths = [c.shape[1] for c in cols]
        width = sum(widths)
        reqs = []
        for nbr, tag in ((self.down, 21), (self.up, 22)):
            if nbr == MPI.PROC_NULL:
                continue
            halo_rows, (m0, nm), _, _ = self._refresh_plan[nbr]
            nh = len(halo_rows)
            buf = self._send_buffer(f"refresh{tag}", nh + nm, width)[:nh + nm]
            j = 0
            for c, w in zip(cols, widths, strict=True):
                np.take(c, halo_rows, axis=0, out=buf[:nh, j:j + w])
                buf[nh:, j:j + w] = c[m0:m0 + nm]
                j += w
            reqs.append(self.comm.Isend(buf, dest=nbr, tag=tag))
        for nbr, tag in ((self.down, 22), (self.up, 21)):
            if nbr == MPI.PROC_NULL:
                continue
            _, _, (h0, nh), (o0, no) = self._refresh_plan[nbr]
            rbuf = self._send_buffer(f"refresh_in{tag}", nh + no, width)[:nh + no]
            self.comm.Recv(rbuf, source=nbr, tag=tag)
            j = 0
            for c, w in zip(cols, widths, strict=True):
                c[h0:h0 + nh] = rbuf[:nh, j:j + w]
                c[o0:o0 + no] = rbuf[nh:, j:j + w]
                j += w
        MPI.Request.Waitall(reqs)

    def _refresh_one(self, field: np.ndarray) -> None:
        """`refresh_halo` of one field of one column: the index lists and buffers of the last
        exchange's plan kept flat, both messages posted before either is waited for (the
        CG's search direction is refreshed every iteration: few calls, no temporaries)."""
        if self._refresh_one_plan is None:
            plan = []
            for nbr, stag, rtag in ((self.down, 21, 22), (self.up, 22, 21)):
                if nbr == MPI.PROC_NULL:
                    continue
                halo_rows, (m0, nm), (h0, nh), (o0, no) = self._refresh_plan[nbr]
                send_idx = np.concatenate((halo_rows, np.arange(m0, m0 + nm)))
                sbuf = self._send_buffer(f"refresh_one{stag}", len(send_idx), 1)
                rbuf = self._send_buffer(f"refresh_one_in{rtag}", nh + no, 1)
                plan.append((nbr, stag, rtag, send_idx, sbuf[:len(send_idx), 0],
                             rbuf[:nh + no, 0], h0, nh, o0, no))
            self._refresh_one_plan = plan
        reqs = []
        for nbr, stag, rtag, send_idx, sbuf, rbuf, *_ in self._refresh_one_plan:
            reqs.append(self.comm.Irecv(rbuf, source=nbr, tag=rtag))
            np.take(field, send_idx, out=sbuf, mode="clip")  # clip: no buffered copy
            reqs.append(self.comm.Isend(sbuf, dest=nbr, tag=stag))
        MPI.Request.Waitall(reqs)
        for _, _, _, _, _, rbuf, h0, nh, o0, no in self._refresh_one_plan:
            field[h0:h0 + nh] = rbuf[:nh]
            field[o0:o0 + no] = rbuf[nh:]

    # --------------------------------------------------------------- load balance

    def imbalance(self, store: ParticleStore) -> float:
        """max / mean of the particles owned per rank (the work of a step scales with
        them). Collective."""
        counts = self.comm.allgather(store.n_owned)
        mean = sum(counts) / len(counts)
        value = max(counts) / mean if mean > 0 else 1.0
        self.last_imbalance = value
        self.max_imbalance = max(self.max_imbalance, value)
        return value

    def rebalance(self, store: ParticleStore, min_width: float, threshold: float) -> bool:
        """Recut the slabs from the particle distribution and move every particle to its
        new owner when the imbalance exceeds `threshold`. Collective; True if recut."""
        if self.size == 1 or self.imbalance(store) <= threshold:
            return False
        n = store.n_owned
        self.set_cuts(balanced_cuts(self.comm, store.x[:n, self.axis], min_width))
        self.redistribute(store)
        self.rebalances += 1
        self.max_after_recut = max(self.max_after_recut, self.imbalance(store))
        return True

    def redistribute(self, store: ParticleStore) -> None:
        """Send every owned particle to the rank whose slab holds it (any distance, one
        all-to-all). Halo and ghost rows are dropped (and the halo refresh plans with
        them, until the next `exchange`). Collective."""
        store.n_halo = store.n_ghost = 0
        self._refresh_plan = {}
        self._refresh_one_plan = None
        if self.size == 1:
            return
        n = store.n_owned
        coord = store.x[:n, self.axis]
        dest = np.searchsorted(self.cuts[1:-1], coord, side="right")
        order = np.argsort(dest, kind="stable")
        send_counts = np.bincount(dest, minlength=self.size).astype(np.int64)
        w = store.row_width
        send = np.zeros((max(n, 1), w))
        pack_rows(store.all_rows, order, n, send)
        recv_counts = np.zeros(self.size, np.int64)
        self.comm.Alltoall(send_counts, recv_counts)
        n_new = int(recv_counts.sum())
        recv = np.zeros((max(n_new, 1), w))
        sd = np.concatenate(([0], np.cumsum(send_counts)[:-1])) * w
        rd = np.concatenate(([0], np.cumsum(recv_counts)[:-1])) * w
        self.comm.Alltoallv([send, (send_counts * w, sd), MPI.DOUBLE],
                            [recv, (recv_counts * w, rd), MPI.DOUBLE])
        store.ensure(n_new + 64)
        unpack_rows(recv, n_new, store.all_rows, 0)
        store.n_owned = n_new

    # --------------------------------------------------------------- reductions

    def allreduce_sum(self, values: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """The element-wise sum over ranks of `values` (any dtype; integers add exactly,
        in any order), into `out` if given (preallocated, for a sum taken every
        iteration). Collective."""
        if out is None:
            out = np.empty_like(values)
        if self.size == 1:
            out[...] = values
        else:
            self.comm.Allreduce(values, out, op=MPI.SUM)
        return out

    def exact_sum(self, parts: np.ndarray) -> float:
        """Correctly rounded sum over ranks of each rank's exact expansion `parts`
        (`psph.kernels.exact_sum`): the same bits on any rank count. Collective."""
        return self.exact_sums([parts])[0]

    def exact_sums(self, parts: list[np.ndarray]) -> list[float]:
        """`exact_sum` of several expansions in one collective."""
        if self.size == 1:
            return [exact_total([p]) for p in parts]
        # one buffer collective (a CG solve makes two of these an iteration): each rank's
        # lengths and parts in fixed rows; a longer expansion anywhere (rare: terms over
        # hundreds of decades) takes the general gather, on every rank alike
        k, slots = len(parts), _SUM_SLOTS
        send = self._send_buffer(f"exact_sum{k}", 1, k * slots)[0]
        for j, p in enumerate(parts):
            send[j * slots] = len(p)
            if len(p) < slots:
                send[j * slots + 1:j * slots + 1 + len(p)] = p
        recv = self._send_buffer(f"exact_sum_in{k}", self.size, k * slots)[:self.size]
        self.comm.Allgather(send, recv)
        lengths = recv[:, ::slots].astype(np.int64)
        if (lengths < slots).all():
            return [exact_total([recv[r, j * slots + 1:j * slots + 1 + lengths[r, j]]
                                  for r in range(self.size)]) for j in range(k)]
        gathered = self.comm.allgather([np.ascontiguousarray(p) for p in parts])
        return [exact_total([g[j] for g in gathered]) for j in range(k)]

    def allreduce_max(self, value: float) -> float:
        return self.comm.allreduce(value, op=MPI.MAX)

    def allreduce_max_ints(self, flags) -> np.ndarray:
        """Element-wise max over ranks of a few integers (one small collective)."""
        local = np.asarray(flags, np.int64)
        out = np.empty_like(local)
        self.comm.Allreduce(local, out, op=MPI.MAX)
        return out

    def any(self, flag: bool) -> bool:
        return bool(self.comm.allreduce(int(flag), op=MPI.MAX))

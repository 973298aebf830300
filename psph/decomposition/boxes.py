"""Boxes along two axes: the domain cut into n0 slabs along axis a0, each slab
cut into n1 boxes along a1, one box a rank (rank = slab n1 + box). The cuts are a
recursive coordinate bisection of the particles: slabs of equal counts, then boxes of
equal counts within each slab (`balance.balanced_cuts`), so the boxes of neighbouring
slabs need not line up.

A slab's halo is a whole cross-section of the domain and does not shrink as ranks are
added; a box's halo is its perimeter's (the scaling model, `bench/performance/
scaling_model_3d.py`). `choose_layout` picks n0 x n1 from the rank count and the
particles' extent; `decomposition.cuts` forces slabs or boxes.

Every step, `exchange` moves the particles that left their box to its owner, then sends
each owned particle within `width` of another rank's box (its faces, edges and corners)
to that rank as halo; `refresh_halo` repeats the second with fresh values. Both go to
the partners only, the ranks whose boxes lie within `width` of this one along both axes
(`box_partners`): point-to-point messages, a count and then the rows, so that a step's
messages do not grow with the rank count (an all-to-all's do). A particle that moved
farther than `width` in one step (found by one collective flag) sends that step's
migration over all ranks instead, as a recut's does; no box needs a minimum width. A
fresh run seeds its particles in the 1D slabs of `Slabs` (the lattice's ids are counted
over disjoint slabs in rank order) and `settle` moves them to their boxes.
"""

import numpy as np
from mpi4py import MPI

from psph.decomposition.balance import balanced_cuts
from psph.decomposition.slabs import Slabs
from psph.kernels.packing import (
    box_halo,
    box_owners,
    compact_rows,
    group_by_rank,
    pack_rows,
    split_by_owner,
    unpack_rows,
)
from psph.state.particles import ParticleStore


def halo_faces(n: int) -> int:
    """Faces of an inner box along an axis cut into n: 0, 1 (two parts) or 2."""
    return min(n - 1, 2)


def choose_layout(extent, size: int, cuts: str) -> tuple[int, int] | None:
    """(n0, n1): n0 slabs along a0, each cut in n1 boxes along a1, n0 n1 = size. "auto"
    takes, of the slabs (size, 1) and the factorisations with n0, n1 > 1, the one with
    the least halo on its busiest rank, w L2 (f0 L1 / n1 + f1 L0 / n0) for boxes L0 / n0
    x L1 / n1 with f the inner faces along each axis (`halo_faces`; slabs on a tie);
    "slabs" is (size, 1); "boxes" the least-halo factorisation with n0, n1 > 1 (None if
    the rank count has no such factors; one rank is one box). extent: the particles'
    extents (L0, L1) along (a0, a1)."""
    if cuts == "slabs" or size == 1:
        return size, 1
    l0, l1 = float(extent[0]), float(extent[1])
    best, best_cost = None, np.inf
    if cuts == "auto":
        best, best_cost = (size, 1), halo_faces(size) * l1
    for n1 in range(2, size // 2 + 1):
        if size % n1:
            continue
        n0 = size // n1
        cost = halo_faces(n0) * l1 / n1 + halo_faces(n1) * l0 / n0
        if cost < best_cost * (1 - 1e-9):
            best, best_cost = (n0, n1), cost
    return best


def box_cuts(comm, c0: np.ndarray, c1: np.ndarray, shape: tuple[int, int]
             ) -> tuple[np.ndarray, np.ndarray]:
    """(cuts0 (n0 + 1,), cuts1 (n0, n1 + 1)) of every rank's points (c0, c1) along the two
    axes: slabs of equal counts along a0, then boxes of equal counts in each (collective;
    the outer cuts -inf and +inf)."""
    n0, n1 = shape
    cuts0 = balanced_cuts(comm, c0, 0.0, parts=n0)
    slab = np.searchsorted(cuts0[1:-1], c0, side="right")
    cuts1 = np.stack([balanced_cuts(comm, c1[slab == s], 0.0, parts=n1) for s in range(n0)])
    return cuts0, cuts1


def box_partners(cuts0: np.ndarray, cuts1: np.ndarray, me: int, width: float) -> np.ndarray:
    """The ranks (ascending, `me` left out) whose boxes lie within `width` of box `me`
    along both axes, their closed extents compared: every rank a row of box `me` can be
    halo for (`packing.box_halo`), or move to in a step shorter than `width`. Symmetric
    to the last bit: r is a partner of me exactly when me is one of r, because both
    compute the same gap max(lo_r - hi_me, lo_me - hi_r) per axis (a one-sided relation
    would leave a receive waiting for ever). An empty box at an infinite cut has a NaN
    gap: no partner."""
    n1 = cuts1.shape[1] - 1
    ranks = np.arange((cuts0.shape[0] - 1) * n1)
    s, b = np.divmod(ranks, n1)
    lo0, hi0 = cuts0[s], cuts0[s + 1]
    lo1, hi1 = cuts1[s, b], cuts1[s, b + 1]
    with np.errstate(invalid="ignore"):
        gap0 = np.maximum(lo0 - hi0[me], lo0[me] - hi0)
        gap1 = np.maximum(lo1 - hi1[me], lo1[me] - hi1)
        near = (gap0 <= width) & (gap1 <= width)
    near[me] = False
    return ranks[near]


class Boxes(Slabs):
    """Boxes along two axes, one a rank (module docstring). `seed_cuts`: the 1D slabs
    along axes[0] over all ranks in which a fresh run seeds its particles (`slab`);
    `cuts0`, `cuts1`: the boxes, if known (a restart's), else set by `settle`."""

    def __init__(self, axes: tuple[int, int], shape: tuple[int, int], seed_cuts: np.ndarray,
                 comm=None, cuts0: np.ndarray | None = None, cuts1: np.ndarray | None = None):
        super().__init__(axes[0], seed_cuts, comm)
        self.axes = (int(axes[0]), int(axes[1]))
        self.shape = (int(shape[0]), int(shape[1]))
        if self.shape[0] * self.shape[1] != self.size:
            raise ValueError(f"layout {self.shape} for {self.size} ranks")
        # index buffers kept from step to step (`_rows_buffer`): no per-step allocation
        # of particle- or halo-length arrays
        self._ints: dict[str, np.ndarray] = {}
        self._send_counts = np.zeros(self.size, np.int64)
        self._recv_counts = np.zeros(self.size, np.int64)
        self._partners: tuple | None = None  # (width, partners, is_partner) of the cuts
        self._halo = None  # the last exchange's halo plan (`refresh_halo`)
        # until `settle` cuts the boxes, this rank's part is its seed slab
        self.cuts0 = self.cuts1 = None
        self.box = (self.slab,)
        if cuts0 is not None:
            self.set_boxes(cuts0, cuts1)

    def set_boxes(self, cuts0: np.ndarray, cuts1: np.ndarray) -> None:
        self._partners = None
        self.cuts0 = np.ascontiguousarray(cuts0, float)
        self.cuts1 = np.ascontiguousarray(cuts1, float)
        s, b = divmod(self.rank, self.shape[1])
        self.box = ((self.axes[0], float(self.cuts0[s]), float(self.cuts0[s + 1])),
                    (self.axes[1], float(self.cuts1[s, b]), float(self.cuts1[s, b + 1])))

    @property
    def region(self) -> tuple[tuple[int, float, float], ...]:
        """This rank's box as (axis, lo, hi) along each cut axis."""
        return self.box

    def describe(self) -> dict:
        """The layout for summary.json (a cut at infinity, of an empty slab, as None)."""
        def finite(cuts):
            return [float(c) if np.isfinite(c) else None for c in cuts[1:-1]]

        return {"layout": "boxes", "shape": list(self.shape), "axes": list(self.axes),
                "cuts0": finite(self.cuts0), "cuts1": [finite(row) for row in self.cuts1]}

    def owned_mask(self, x: np.ndarray) -> np.ndarray:
        mask = np.ones(len(x), bool)
        for axis, lo, hi in self.box:
            mask &= (x[:, axis] >= lo) & (x[:, axis] < hi)
        return mask

    # --------------------------------------------------------------- moving rows

    def _rows_buffer(self, name: str, n: int) -> np.ndarray:
        """A kept int64 buffer of at least n entries, grown by half when short."""
        buf = self._ints.get(name)
        if buf is None or buf.shape[0] < n:
            buf = np.zeros(n + n // 2 + 64, np.int64)
            self._ints[name] = buf
        return buf

    def _owners(self, store: ParticleStore) -> np.ndarray:
        n = store.n_owned
        owner = self._rows_buffer("owner", n)
        box_owners(store.x, n, self.axes[0], self.axes[1], self.cuts0, self.cuts1, owner)
        return owner[:n]

    def _partners_within(self, width: float) -> tuple[np.ndarray, np.ndarray]:
        """(partners, is_partner (size,) bool) for the current cuts (`box_partners`)."""
        if self._partners is None or self._partners[0] != width:
            partners = box_partners(self.cuts0, self.cuts1, self.rank, width)
            is_partner = np.zeros(self.size, bool)
            is_partner[partners] = True
            self._partners = (width, partners, is_partner)
        return self._partners[1], self._partners[2]

    def _alltoall_rows(self, store: ParticleStore, rows: np.ndarray, send_counts: np.ndarray,
                       kept: bool = True, partners: np.ndarray | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
        """Send store rows `rows`, grouped by destination rank (`send_counts` of them to
        each rank, in that order); returns the received rows (n, width) in source-rank
        order and the counts received from each rank (a kept array: read it before the
        next call). Collective. `kept`: the message buffers are kept for the next step's
        (the per-step exchange); a recut's, whose messages may hold most of the rank's
        rows, are temporaries. `partners`: the only ranks rows go to and come from
        (point-to-point messages, the same bits as the all-to-all); None: any rank."""
        w = store.row_width
        send = self._send_buffer("boxes_send", len(rows), w) if kept else \
            np.empty((max(len(rows), 1), w))
        pack_rows(store.all_rows, rows, len(rows), send)
        recv_counts = self._recv_counts
        if partners is None:
            self.comm.Alltoall(send_counts, recv_counts)
        else:
            recv_counts[:] = 0
            reqs = [self.comm.Irecv(recv_counts[r:r + 1], source=r, tag=41) for r in partners]
            reqs += [self.comm.Isend(send_counts[r:r + 1], dest=r, tag=41) for r in partners]
            MPI.Request.Waitall(reqs)
        n_in = int(recv_counts.sum())
        recv = self._send_buffer("boxes_recv", n_in, w) if kept else \
            np.empty((max(n_in, 1), w))
        if partners is None:
            self.comm.Alltoallv([send, (send_counts * w, _displacements(send_counts) * w),
                                 MPI.DOUBLE],
                                [recv, (recv_counts * w, _displacements(recv_counts) * w),
                                 MPI.DOUBLE])
            return recv[:n_in], recv_counts
        reqs = []
        at = _displacements(recv_counts)
        for r in partners:
            if recv_counts[r]:
                reqs.append(self.comm.Irecv(recv[at[r]:at[r] + recv_counts[r]], source=r,
                                            tag=42))
        at = _displacements(send_counts)
        for r in partners:
            if send_counts[r]:
                reqs.append(self.comm.Isend(send[at[r]:at[r] + send_counts[r]], dest=r,
                                            tag=42))
        MPI.Request.Waitall(reqs)
        return recv[:n_in], recv_counts

    def _migrate(self, store: ParticleStore, owner: np.ndarray, kept: bool = True,
                 width: float | None = None) -> None:
        """The owned rows whose `owner` is another rank go there; the rest stay in order,
        the received ones follow them as owned. Collective. `width`: the step's halo
        width, whose partners take the rows unless a row goes farther on some rank
        (then, as with None, all ranks)."""
        n = store.n_owned
        keep = self._rows_buffer("keep", n)
        leave = self._rows_buffer("leave", n)
        leave_dest = self._rows_buffer("leave_dest", n)
        nk, nl = split_by_owner(owner, n, self.rank, keep, leave, leave_dest)
        grouped = self._rows_buffer("grouped", nl)
        group_by_rank(leave_dest, leave, nl, self._send_counts, grouped)
        partners = None
        if width is not None:
            partners, is_partner = self._partners_within(width)
            far = bool(np.any(self._send_counts[~is_partner]))
            if self.any(far):
                partners = None
        recv, _ = self._alltoall_rows(store, grouped[:nl], self._send_counts, kept,
                                      partners)
        if nl:
            compact_rows(store.all_rows, keep, nk)
            store.n_owned = nk
        store.ensure(store.n_owned + len(recv) + 64)
        unpack_rows(recv, len(recv), store.all_rows, store.n_owned)
        store.n_owned += len(recv)

    def settle(self, store: ParticleStore) -> None:
        """Fresh particles, seeded in the 1D slabs of `slab`, to their boxes: the box cuts
        from their distribution, then one all-to-all. Collective."""
        self._recut(store)
        self.redistribute(store)

    def _recut(self, store: ParticleStore) -> None:
        x = store.x[:store.n_owned]
        self.set_boxes(*box_cuts(self.comm, x[:, self.axes[0]], x[:, self.axes[1]],
                                 self.shape))

    def redistribute(self, store: ParticleStore) -> None:
        """Every owned particle to the rank whose box holds it (any distance); halo and
        ghost rows are dropped with the halo plan. Collective."""
        store.n_halo = store.n_ghost = 0
        self._halo = None
        if self.size == 1:
            return
        self._migrate(store, self._owners(store), kept=False)

    def rebalance(self, store: ParticleStore, min_width: float, threshold: float) -> bool:
        """Recut the boxes (slabs, then boxes in each) and move every particle to its new
        owner when the imbalance exceeds `threshold`. Collective; True if recut."""
        if self.size == 1 or self.imbalance(store) <= threshold:
            return False
        self._recut(store)
        self.redistribute(store)
        self.rebalances += 1
        self.max_after_recut = max(self.max_after_recut, self.imbalance(store))
        return True

    # --------------------------------------------------------------- per step

    def exchange(self, store: ParticleStore, width: float) -> None:
        """Migration to the owners, then the halo: every owned row within `width` of
        another rank's box, appended there after its owned rows (module docstring)."""
        store.n_halo = store.n_ghost = 0
        if self.size == 1:
            return
        self._migrate(store, self._owners(store), width=width)
        n = store.n_owned
        dest = self._rows_buffer("halo_dest", n)
        rows = self._rows_buffer("halo_rows", n)
        m = box_halo(store.x, n, self.axes[0], self.axes[1], self.cuts0, self.cuts1, width,
                     self.rank, dest, rows)
        if m < 0:  # a row is halo for more than one box: grow and count again
            dest = self._rows_buffer("halo_dest", -m)
            rows = self._rows_buffer("halo_rows", -m)
            m = box_halo(store.x, n, self.axes[0], self.axes[1], self.cuts0, self.cuts1,
                         width, self.rank, dest, rows)
        # the halo plan is kept until the next exchange (`refresh_halo`): its own buffers
        send_rows = self._rows_buffer("halo_send", m)[:m]
        send_counts = self._rows_buffer("halo_counts", self.size)[:self.size]
        group_by_rank(dest, rows, m, send_counts, send_rows)
        partners, is_partner = self._partners_within(width)
        # box_halo's ranks are partners (box_partners); were one not, on any rank, the
        # halo goes over all ranks this step rather than lose its rows or hang
        if self.any(bool(np.any(send_counts[~is_partner]))):
            partners = None
        recv, recv_counts = self._alltoall_rows(store, send_rows, send_counts,
                                                partners=partners)
        store.ensure(n + len(recv) + 64)
        unpack_rows(recv, len(recv), store.all_rows, n)
        store.n_halo = len(recv)
        self._halo = (send_rows, send_counts, recv_counts.copy(), n)

    def refresh_halo(self, *fields: np.ndarray) -> None:
        """Overwrite the halo rows of each field ((cap,) or (cap, k)) with the owners'
        current values, for the halo of the last `exchange` (no particle has moved since):
        one all-to-all for all the fields."""
        if self.size == 1:
            return
        send_rows, send_counts, recv_counts, first = self._halo
        cols = [f if f.ndim == 2 else f[:, None] for f in fields]
        widths = [c.shape[1] for c in cols]
        width = sum(widths)
        n_out, n_in = len(send_rows), int(recv_counts.sum())
        sbuf = self._send_buffer("boxes_refresh", n_out, width)[:n_out]
        j = 0
        for c, w in zip(cols, widths, strict=True):
            np.take(c, send_rows, axis=0, out=sbuf[:, j:j + w])
            j += w
        rbuf = self._send_buffer("boxes_refresh_in", n_in, width)[:n_in]
        # messages to and from the ranks this one shares a halo with only (a CG solve
        # refreshes every iteration: no all-to-all over every rank)
        reqs = []
        at = _displacements(recv_counts)
        for r in np.flatnonzero(recv_counts):
            reqs.append(self.comm.Irecv(rbuf[at[r]:at[r] + recv_counts[r]], source=r, tag=31))
        at = _displacements(send_counts)
        for r in np.flatnonzero(send_counts):
            reqs.append(self.comm.Isend(sbuf[at[r]:at[r] + send_counts[r]], dest=r, tag=31))
        MPI.Request.Waitall(reqs)
        j = 0
        for c, w in zip(cols, widths, strict=True):
            c[first:first + n_in] = rbuf[:, j:j + w]
            j += w

    def _refresh_one(self, field: np.ndarray) -> None:
        self.refresh_halo(field)


def _displacements(counts: np.ndarray) -> np.ndarray:
    return np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.int64)

"""Gather / scatter particle rows to and from contiguous message buffers.

Fields are passed as a tuple of 2D float64 arrays (cap, ncomp); scalar fields are passed as
(cap, 1) views. Used by halo exchange and migration (which know no equation).
"""

import numba as nb
import numpy as np


@nb.njit(cache=True)
def pack_rows(fields, idx, count, out):
    """out[r, :] = the concatenation of fields[f][idx[r], :] for r < count.

    Parameters
    ----------
    fields : tuple of (cap, ncomp) float64 arrays
        the fields, in SI units.
    idx : int64 array
        rows to pack.
    count : int
        number of rows.
    out : (>= count, sum of ncomp) float64 array
        the message buffer.
    """
    for r in range(count):
        i = idx[r]
        col = 0
        for f in fields:
            for c in range(f.shape[1]):
                out[r, col] = f[i, c]
                col += 1


@nb.njit(cache=True)
def unpack_rows(buf, count, fields, start):
    """fields[f][start + r, :] = the matching columns of buf[r, :] for r < count.

    Parameters
    ----------
    buf : (>= count, sum of ncomp) float64 array
        the message buffer (`pack_rows`).
    count : int
        number of rows.
    fields : tuple of (cap, ncomp) float64 arrays
        the fields.
    start : int
        first row written.
    """
    for r in range(count):
        col = 0
        for f in fields:
            for c in range(f.shape[1]):
                f[start + r, c] = buf[r, col]
                col += 1


@nb.njit(cache=True)
def compact_rows(fields, keep, count):
    """fields[f][r, :] = fields[f][keep[r], :] for r < count, in place.

    Parameters
    ----------
    fields : tuple of (cap, ncomp) float64 arrays
        the fields.
    keep : int64 array
        rows to keep, increasing (so no row is read after it is overwritten).
    count : int
        number of rows kept.
    """
    for f in fields:
        for r in range(count):
            i = keep[r]
            if i != r:
                for c in range(f.shape[1]):
                    f[r, c] = f[i, c]


@nb.njit(cache=True)
def split_by_owner(owner, n, me, keep, leave, leave_dest):
    """Rows 0..n-1 by their owner rank, in row order.

    Parameters
    ----------
    owner : int64 array
        each row's owner rank.
    n : int
        number of rows.
    me : int
        this rank.
    keep : int64 array
        receives the rows of rank `me`.
    leave, leave_dest : int64 arrays
        receive the other rows and their owners.

    Returns
    -------
    nk, nl : int
        the numbers kept and leaving.
    """
    nk = nl = 0
    for i in range(n):
        r = owner[i]
        if r == me:
            keep[nk] = i
            nk += 1
        else:
            leave[nl] = i
            leave_dest[nl] = r
            nl += 1
    return nk, nl


@nb.njit(cache=True)
def group_by_rank(dest, rows, m, counts, grouped):
    """A counting sort of rows by destination rank, row order kept within a rank (the
    order of rows[argsort(dest, kind="stable")]).

    Parameters
    ----------
    dest : int64 array
        each row's destination rank.
    rows : int64 array
        the rows.
    m : int
        number of rows.
    counts : (n_ranks,) int64 array
        receives how many go to each rank.
    grouped : int64 array
        receives the rows grouped by rank.
    """
    counts[:] = 0
    for k in range(m):
        counts[dest[k]] += 1
    at = np.empty(counts.shape[0], np.int64)
    total = 0
    for r in range(counts.shape[0]):
        at[r] = total
        total += counts[r]
    for k in range(m):
        r = dest[k]
        grouped[at[r]] = rows[k]
        at[r] += 1


@nb.njit(cache=True)
def select_slab_rows(coord, n, lo, hi, width, is_first, is_last, migr_down, migr_up,
                     halo_down, halo_up, keep):
    """Classify owned particles 0..n-1 against the slab [lo, hi) along one axis.

    Particles below lo (above hi) migrate to the lower (upper) rank; of the rest, those
    within `width` of a cut are halo for that neighbour. The first/last rank keeps what
    is beyond its outer end.

    Parameters
    ----------
    coord : float64 array
        the particles' coordinates along the slab axis (m).
    n : int
        number of owned particles.
    lo, hi : float
        the slab's bounds (m).
    width : float
        halo width (m).
    is_first, is_last : bool
        the slab is the first / last along the axis.
    migr_down, migr_up, halo_down, halo_up, keep : int64 arrays
        receive the index lists.

    Returns
    -------
    n_migr_down, n_migr_up, n_halo_down, n_halo_up, n_keep : int
    """
    nmd = nmu = nhd = nhu = nk = 0
    for i in range(n):
        c = coord[i]
        if c < lo and not is_first:
            migr_down[nmd] = i
            nmd += 1
        elif c >= hi and not is_last:
            migr_up[nmu] = i
            nmu += 1
        else:
            keep[nk] = i
            nk += 1
            if c < lo + width and not is_first:
                halo_down[nhd] = i
                nhd += 1
            if c >= hi - width and not is_last:
                halo_up[nhu] = i
                nhu += 1
    return nmd, nmu, nhd, nhu, nk


@nb.njit(cache=True)
def box_owners(x, n, a0, a1, cuts0, cuts1, owner):
    """The owner rank of each row in a two-axis layout: slab s along axis a0, then box b
    of that slab along a1; rank = s n1 + b.

    Parameters
    ----------
    x : (cap, dim) float64 array
        positions (m).
    n : int
        number of rows.
    a0, a1 : int
        the two axes.
    cuts0 : (n0 + 1,) float64 array
        the slabs' cuts along a0 (m), outer cuts -inf and +inf.
    cuts1 : (n0, n1 + 1) float64 array
        each slab's cuts along a1 (m).
    owner : int64 array
        receives the ranks.
    """
    n1 = cuts1.shape[1] - 1
    for i in range(n):
        s = np.searchsorted(cuts0[1:-1], x[i, a0], side="right")
        b = np.searchsorted(cuts1[s, 1:-1], x[i, a1], side="right")
        owner[i] = s * n1 + b


@nb.njit(cache=True)
def box_halo(x, n, a0, a1, cuts0, cuts1, width, me, dest, rows):
    """The halo of rows 0..n-1 (all owned by rank `me`) in a two-axis layout
    (`box_owners`): each (rank, row) with the row within `width` of that rank's box along
    both axes (edges and corners included), rank != me, in row order.

    Parameters
    ----------
    x, n, a0, a1, cuts0, cuts1
        as `box_owners`.
    width : float
        halo width (m).
    me : int
        this rank.
    dest, rows : int64 arrays
        receive the (rank, row) entries.

    Returns
    -------
    int
        the number m of entries, or -m if dest is too short.
    """
    n1 = cuts1.shape[1] - 1
    m = 0
    cap = dest.shape[0]
    for i in range(n):
        c0 = x[i, a0]
        c1 = x[i, a1]
        s_lo = np.searchsorted(cuts0[1:-1], c0 - width, side="right")
        s_hi = np.searchsorted(cuts0[1:-1], c0 + width, side="right")
        for s in range(s_lo, s_hi + 1):
            b_lo = np.searchsorted(cuts1[s, 1:-1], c1 - width, side="right")
            b_hi = np.searchsorted(cuts1[s, 1:-1], c1 + width, side="right")
            for b in range(b_lo, b_hi + 1):
                r = s * n1 + b
                if r == me:
                    continue
                if m < cap:
                    dest[m] = r
                    rows[m] = i
                m += 1
    return m if m <= cap else -m

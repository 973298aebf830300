"""Gather / scatter particle rows to and from contiguous message buffers.

Fields are passed as a tuple of 2D float64 arrays (cap, ncomp); scalar fields are passed as
(cap, 1) views. Used by halo exchange and migration (which know no equation).
"""

import numba as nb


@nb.njit(cache=True)
def pack_rows(fields, idx, count, out):
    """out[r, :] = concatenation of fields[f][idx[r], :] for r < count."""
    for r in range(count):
        i = idx[r]
        col = 0
        for f in fields:
            for c in range(f.shape[1]):
                out[r, col] = f[i, c]
                col += 1


@nb.njit(cache=True)
def unpack_rows(buf, count, fields, start):
    """fields[f][start + r, :] = the matching columns of buf[r, :] for r < count."""
    for r in range(count):
        col = 0
        for f in fields:
            for c in range(f.shape[1]):
                f[start + r, c] = buf[r, col]
                col += 1


@nb.njit(cache=True)
def select_slab_rows(coord, n, lo, hi, width, is_first, is_last, migr_down, migr_up,
                     halo_down, halo_up, keep):
    """Classify owned particles 0..n-1 against the slab [lo, hi) along one axis.

    Fills index lists and returns (n_migr_down, n_migr_up, n_halo_down, n_halo_up, n_keep):
    particles below lo (above hi) migrate to the lower (upper) rank; of the rest, those
    within `width` of a cut are halo for that neighbour. The first/last rank keeps what
    is beyond its outer end.
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

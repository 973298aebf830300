"""Non-local (integral-averaged) equivalent plastic strain for the softening laws of
Eq. (17)-(19) of Lian et al. (2023) (`material.plasticity.regularisation`).

With a local softening law the plastic strain of a shear band concentrates in one row of
particles, so the energy the band dissipates scales with dx. Here the softening of
Eq. (17)-(19) is driven by the over-non-local strain (Vermeer & Brinkgreve 1994;
Brinkgreve 1994; Galavi & Schweiger 2010)

    eps_hat_i = (1 - m) eps_i + m eps_bar_i,
    eps_bar_i = sum_j V_j W(r_ij, l_c) eps_j / sum_j V_j W(r_ij, l_c),

W the cubic spline of Eq. (21) with smoothing length l_c (support 2 l_c), the internal
length of the material in metres, independent of dx; the sum runs over the real particles
(owned and halo; not boundary particles) of the same material within 2 l_c, i included,
and over their mirror images across the walls (free-slip and fixed planes of
`boundaries`; across two walls of different axes at a corner), as the wall ghosts
continue every other field. Without the images the support of a particle on a wall is
one-sided: a band along the wall (a slide's basal row) has eps_bar about eps_p / 2, so
eps_hat = 2 eps_bar - eps_p is clipped to 0 and the band never softens (psi stays psi_0,
and a contractive row compacts to n = 0). With them a band
on a wall is the half of a band symmetric about it. The weights are sum-normalised, so a
constant field is reproduced exactly; they are symmetric, so a linear field is
reproduced where the support is full (and lies off the walls).
m >= 1: m = 1 the plain non-local average; m > 1 weights the average above the local
value, which keeps the band at a width set by l_c (Jirasek & Rolshoven 2003).
eps_hat is clipped at 0 (no strength above the peak). The local eps_p still accumulates
the return mapping's increments (`update.advance`).

One source for 2D and 3D (`make_nonlocal_strain(dim)`, `dims.py`): in 3D the cells are
searched layer by layer in z too, and the images are those across each wall, across two
walls of different axes (an edge) and across three (a corner); the 2D specialisation
performs the plane-strain operations in their order, so its bits do not depend on 3D.
"""

import math

import numba as nb

from psph.kernels.spline import w_cubic_dim


def make_nonlocal_strain(dim: int):
    """`nonlocal_strain` in `dim` = 2 or 3 dimensions.

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `nonlocal_strain`.
    """

    @nb.njit(cache=True, inline="always")
    def image_weight(x, i, j, axes, pos, count, vol_j, lc):
        """The weight V_j W(|x_i - x_j*|, l_c) of the image x_j* of j across `count` walls.

        Parameters
        ----------
        x : (cap, dim) float64 array
            positions (m).
        i, j : int
            the particle and the image's source.
        axes : int64 array
            the walls' normal axes (distinct), first `count` used.
        pos : float64 array
            the walls' positions x[axes[k]] = pos[k] (m).
        count : int
            number of walls, 1 to 3.
        vol_j : float
            the source's volume (m^3; m^2 in 2D).
        lc : float
            internal length l_c (m).

        Returns
        -------
        float
            the weight (dimensionless); 0 beyond the support 2 l_c.
        """
        d0 = x[j, 0] - x[i, 0]
        d1 = x[j, 1] - x[i, 1]
        d2 = x[j, 2] - x[i, 2] if dim == 3 else 0.0
        for k in range(count):
            if axes[k] == 0:
                d0 = 2.0 * pos[k] - x[j, 0] - x[i, 0]
            elif axes[k] == 1:
                d1 = 2.0 * pos[k] - x[j, 1] - x[i, 1]
            else:
                d2 = 2.0 * pos[k] - x[j, 2] - x[i, 2]
        r2 = d0 * d0 + d1 * d1
        if dim == 3:
            r2 += d2 * d2
        if r2 >= 4.0 * lc * lc:
            return 0.0
        return vol_j * w_cubic_dim(math.sqrt(r2), lc, dim)

    @nb.njit(cache=True)
    def nonlocal_strain(n_owned, n_real, fields, lengths, weights, cells, rings, plastic_cell,
                        wall_axis, wall_pos, out):
        """The over-non-local strain eps_hat_i of particles 0..n_owned-1 (module docstring).

        An image of j lies no closer to i than j itself (both on the soil's side), so the
        cells that hold the real particles within 2 l_c hold every image's source too.
        Each sum visits the cells row by row in the global numbering and a cell in key
        order: the same particles in the same order on any number of ranks (bitwise 1 vs
        N, with a halo of at least 2 l_c). A particle with no plastic strain in the cells
        it searches keeps eps_hat = eps_p = 0 without the sum (which would give exactly
        that): the sums run only where something has yielded within the support.

        Parameters
        ----------
        n_owned : int
            owned rows 0..n_owned-1.
        n_real : int
            rows 0..n_real-1 are real particles (owned and halo); boundary rows follow.
        fields : `bundles.NonlocalFields`
            positions x, (cap, dim) float64 (m); particle volumes vol, (cap,) float64
            (m^3; m^2 per unit thickness in 2D); the local equivalent plastic strain
            eps_p, (cap,) float64 (dimensionless); each particle's material index
            material, (cap,).
        lengths, weights : (n_materials,) float64 arrays
            l_c (m) and m of each material (l_c = 0: local, out = eps_p).
        cells : `bundles.CellList`
            the step's cell list (cells of side 2h, particles in key order in a cell),
            int64 arrays.
        rings : int
            cells to search on each side, >= 2 max l_c / (2h) (`rings_for`).
        plastic_cell : int8 array
            scratch of at least prod(ncell) entries.
        wall_axis : int64 array
            normal axes of the walls whose images enter the sums (empty: none).
        wall_pos : float64 array
            their positions (m).
        out : (>= n_owned,) float64 array
            receives eps_hat (dimensionless, >= 0).
        """
        x, vol, eps_p, material = fields.x, fields.vol, fields.eps_p, fields.material
        cell_of, cell_start = cells.cell_of, cells.cell_start
        order, ncell = cells.order, cells.ncell
        ncx = ncell[0]
        ncy = ncell[1]
        ncz = ncell[2] if dim == 3 else 1
        nw = len(wall_axis)
        axes = wall_axis.copy()[:3]  # the walls of one image (at most one a axis)
        pos = wall_pos.copy()[:3]
        for c in range(ncx * ncy * ncz):
            plastic_cell[c] = 0
        for j in range(n_real):
            if eps_p[j] != 0.0:
                plastic_cell[cell_of[j]] = 1
        for i in range(n_owned):
            k = int(material[i])
            lc = lengths[k]
            if not lc > 0.0:
                out[i] = eps_p[i]
                continue
            c = cell_of[i]
            cx = c % ncx
            cy = (c // ncx) % ncy
            cz = c // (ncx * ncy) if dim == 3 else 0
            z0 = max(cz - rings, 0) if dim == 3 else 0
            z1 = min(cz + rings + 1, ncz) if dim == 3 else 1
            near = False
            for nz in range(z0, z1):
                for ny in range(max(cy - rings, 0), min(cy + rings + 1, ncy)):
                    for nx in range(max(cx - rings, 0), min(cx + rings + 1, ncx)):
                        if plastic_cell[(nz * ncy + ny) * ncx + nx]:
                            near = True
            if not near:
                out[i] = eps_p[i]
                continue
            support2 = 4.0 * lc * lc
            near_walls = 0  # bit a: i within 2 l_c of wall a, whose images can reach it
            for a in range(nw):
                if abs(x[i, wall_axis[a]] - wall_pos[a]) < 2.0 * lc:
                    near_walls |= 1 << a
            num = 0.0
            den = 0.0
            for nz in range(z0, z1):
                for ny in range(max(cy - rings, 0), min(cy + rings + 1, ncy)):
                    for nx in range(max(cx - rings, 0), min(cx + rings + 1, ncx)):
                        nc = (nz * ncy + ny) * ncx + nx
                        for s in range(cell_start[nc], cell_start[nc + 1]):
                            j = order[s]
                            if j >= n_real or int(material[j]) != k:
                                continue
                            d0 = x[j, 0] - x[i, 0]
                            d1 = x[j, 1] - x[i, 1]
                            r2 = d0 * d0 + d1 * d1
                            if dim == 3:
                                d2 = x[j, 2] - x[i, 2]
                                r2 += d2 * d2
                            if r2 >= support2:
                                continue
                            w = vol[j] * w_cubic_dim(math.sqrt(r2), lc, dim)
                            num += w * eps_p[j]
                            den += w
                            for a in range(nw):
                                if not (near_walls >> a) & 1:
                                    continue
                                axes[0], pos[0] = wall_axis[a], wall_pos[a]
                                g = image_weight(x, i, j, axes, pos, 1, vol[j], lc)
                                num += g * eps_p[j]
                                den += g
                                for b in range(a + 1, nw):  # an edge image across both
                                    if wall_axis[b] == wall_axis[a] \
                                            or not (near_walls >> b) & 1:
                                        continue
                                    axes[1], pos[1] = wall_axis[b], wall_pos[b]
                                    g = image_weight(x, i, j, axes, pos, 2, vol[j], lc)
                                    num += g * eps_p[j]
                                    den += g
                                    if dim == 2:
                                        continue
                                    for e in range(b + 1, nw):  # a corner: three walls
                                        if wall_axis[e] == wall_axis[a] \
                                                or wall_axis[e] == wall_axis[b] \
                                                or not (near_walls >> e) & 1:
                                            continue
                                        axes[2], pos[2] = wall_axis[e], wall_pos[e]
                                        g = image_weight(x, i, j, axes, pos, 3, vol[j], lc)
                                        num += g * eps_p[j]
                                        den += g
            m = weights[k]
            e = (1.0 - m) * eps_p[i] + m * (num / den)
            out[i] = e if e > 0.0 else 0.0

    return nonlocal_strain


nonlocal_strain = make_nonlocal_strain(2)
nonlocal_strain_3d = make_nonlocal_strain(3)


def rings_for(length: float, cell_size: float) -> int:
    """Cells to search on each side for a support of 2 l_c.

    Parameters
    ----------
    length : float
        internal length l_c (m).
    cell_size : float
        cell side (m).

    Returns
    -------
    int
        ceil(2 l_c / cell_size), at least 1.
    """
    return max(1, math.ceil(2.0 * length / cell_size))

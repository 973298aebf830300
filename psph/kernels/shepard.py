"""Shepard filter of the pore pressure, Eq. (46) of Lian et al. (2023), and the stress
regularisation, in 2D and 3D (one source per kernel, `dims.py`).

p_i <- sum_j V_j W_ij p_j / sum_j V_j W_ij over the neighbours j within 2h (i included).
Zeroth-order (constant-preserving) smoothing of the pressure noise; Section 3.5.2 applies
it every m = 20-40 steps. Neighbours include halo rows and wall ghosts (which carry the
mirrored pressure), so a wall behaves as a symmetry plane. The effective stress can be
regularised in the same step, with the same sum or with its first-order (MLS) form.
All three filters share one pair sweep, `kernel_moments`, which visits the pairs in the
half-stencil order of the cells of side 2h (`neighbours.forward_slots` at span 1: the
step's sweep's order in 2D; the 3D sweep runs on cells of side h).
"""

import math

import numba as nb

from psph.kernels.neighbours import forward_slots, half_stencil_rows, next_cell
from psph.kernels.spline import w_cubic_dim


def moment_width(dim: int, first_order: bool, m: int) -> int:
    """Columns of `kernel_moments`'s output.

    Parameters
    ----------
    dim : int
        2 or 3.
    first_order : bool
        the first-order (MLS) moments, q = (1, x_j - x_i).
    m : int
        number of filtered columns.

    Returns
    -------
    int
        1 + m (zeroth order); first order: the (dim + 1)(dim + 2)/2 entries of A and
        dim + 1 a column.
    """
    if not first_order:
        return 1 + m
    return (dim + 1) * (dim + 2) // 2 + (dim + 1) * m


def make_kernel_moments(dim: int):
    """`kernel_moments` in `dim` = 2 or 3 dimensions.

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `kernel_moments`.
    """
    n_rows = half_stencil_rows(dim)
    n_a = (dim + 1) * (dim + 2) // 2  # the unique entries of the symmetric A

    @nb.njit(cache=True, inline="always")
    def add_moments(row, w, d0, d1, d2, fj, first_order):
        """Add neighbour j to one row of the moments.

        Parameters
        ----------
        row : float64 array
            the row of `kernel_moments`'s output.
        w : float
            weight V_j W_ij (dimensionless).
        d0, d1, d2 : float
            offset x_j - x_i (m); d2 = 0 in 2D.
        fj : float64 array
            j's values of the filtered columns.
        first_order : bool
            first-order (MLS) moments.
        """
        m = fj.shape[0]
        if not first_order:
            row[0] += w
            for c in range(m):
                row[1 + c] += w * fj[c]
            return
        row[0] += w
        row[1] += w * d0
        row[2] += w * d1
        if dim == 2:
            row[3] += w * d0 * d0
            row[4] += w * d0 * d1
            row[5] += w * d1 * d1
            for c in range(m):
                row[6 + 3 * c] += w * fj[c]
                row[7 + 3 * c] += w * d0 * fj[c]
                row[8 + 3 * c] += w * d1 * fj[c]
            return
        # A: 00 01 02 03 11 12 13 22 23 33 over q = (1, d0, d1, d2)
        row[3] += w * d2
        row[4] += w * d0 * d0
        row[5] += w * d0 * d1
        row[6] += w * d0 * d2
        row[7] += w * d1 * d1
        row[8] += w * d1 * d2
        row[9] += w * d2 * d2
        for c in range(m):
            row[10 + 4 * c] += w * fj[c]
            row[11 + 4 * c] += w * d0 * fj[c]
            row[12 + 4 * c] += w * d1 * fj[c]
            row[13 + 4 * c] += w * d2 * fj[c]

    @nb.njit(cache=True)
    def kernel_moments(n_owned, x, f, vol, cell_start, order, ncell, h, first_order, mom):
        """Kernel-weighted moments of the columns of f over the neighbours j within 2h of
        every owned particle i (i included; halo rows and wall ghosts are neighbours),
        w = V_j W_ij.

        Parameters
        ----------
        n_owned : int
            owned rows 0..n_owned-1.
        x : (cap, dim) float64 array
            positions (m).
        f : (cap, m) float64 array
            the filtered columns (any unit).
        vol : (cap,) float64 array
            particle volumes (m^3; m^2 per unit thickness in 2D).
        cell_start, order, ncell : int64 arrays
            a cell list with cells of side 2h.
        h : float
            smoothing length (m).
        first_order : bool
            False: mom[i, 0] = sum w, mom[i, 1 + c] = sum w f[j, c] (the sums of Eq. 46);
            True, q = (1, x_j - x_i): mom[i, :n_a] = A = sum w q q^T (its upper triangle
            row by row) and mom[i, n_a + (dim + 1) c + k] = sum w q_k f[j, c].
        mom : (>= n_owned, `moment_width(dim, first_order, m)`) float64 array
            receives the moments.
        """
        m = f.shape[1]
        w0 = w_cubic_dim(0.0, h, dim)
        width = n_a + (dim + 1) * m if first_order else 1 + m
        for i in range(n_owned):
            for c in range(width):
                mom[i, c] = 0.0
            add_moments(mom[i], vol[i] * w0, 0.0, 0.0, 0.0, f[i], first_order)
        ncx = ncell[0]
        ncy = ncell[1]
        ncz = ncell[2] if dim == 3 else 1
        support2 = 4.0 * h * h
        cx, cy, cz = -1, 0, 0
        for c0 in range(ncx * ncy * ncz):  # row-major, x fastest: the global cell order
            cx, cy, cz = next_cell(cx, cy, cz, ncx, ncy)
            for sa in range(cell_start[c0], cell_start[c0 + 1]):
                a = order[sa]
                for row in range(n_rows):
                    s0, s1 = forward_slots(row, c0, sa, cx, cy, cz, ncx, ncy, ncz,
                                           cell_start, dim)
                    for sb in range(s0, s1):
                        b = order[sb]
                        if a >= n_owned and b >= n_owned:
                            continue
                        d0 = x[b, 0] - x[a, 0]
                        d1 = x[b, 1] - x[a, 1]
                        d2 = x[b, 2] - x[a, 2] if dim == 3 else 0.0
                        r2 = d0 * d0 + d1 * d1
                        if dim == 3:
                            r2 += d2 * d2
                        if r2 >= support2:
                            continue
                        w = w_cubic_dim(math.sqrt(r2), h, dim)
                        if a < n_owned:
                            add_moments(mom[a], vol[b] * w, d0, d1, d2, f[b], first_order)
                        if b < n_owned:
                            add_moments(mom[b], vol[a] * w, -d0, -d1, -d2, f[a],
                                        first_order)

    return kernel_moments


kernel_moments = make_kernel_moments(2)
kernel_moments_3d = make_kernel_moments(3)


def make_filters(dim: int):
    """The filters in `dim` = 2 or 3 dimensions.

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    shepard_pressure, shepard_stress, mls_stress : functions
        compiled.
    """
    moments = make_kernel_moments(dim)
    n_stress = 4 if dim == 2 else 6  # xx, yy, zz, xy (2D); + yz, zx (3D)

    @nb.njit(cache=True)
    def shepard_pressure(n_total, n_owned, x, p, p_prev, vol, drained_from, t, cells, h, mom):
        """Filter p of particles 0..n_owned-1 in place (Eq. 46). Particles with an imposed
        pressure (drained_from <= t) keep it. p_prev moves with p, so the TPI increment
        p - p_prev of Eq. (39) is not changed by the filter.

        Parameters
        ----------
        n_total : int
            rows in use (owned, halo, ghosts).
        n_owned : int
            owned rows 0..n_owned-1.
        x : (cap, dim) float64 array
            positions (m).
        p, p_prev : (cap,) float64 arrays
            pore pressure now and one step before (Pa), filtered in place.
        vol : (cap,) float64 array
            particle volumes (m^3; m^2 per unit thickness in 2D).
        drained_from : (cap,) float64 array
            time from which p = 0 is imposed (s).
        t : float
            time (s).
        cells : `bundles.CellList`
            a cell list with cells of side 2h (cell_of is not read).
        h : float
            smoothing length (m).
        mom : (>= n_owned, 2) float64 array
            scratch.
        """
        moments(n_owned, x, p.reshape((p.shape[0], 1)), vol, cells.cell_start, cells.order,
                cells.ncell, h, False, mom)
        for i in range(n_owned):
            if drained_from[i] > t and mom[i, 0] > 0.0:
                filtered = mom[i, 1] / mom[i, 0]
                p_prev[i] += filtered - p[i]
                p[i] = filtered

    @nb.njit(cache=True)
    def shepard_stress(n_total, n_owned, x, stress, vol, cells, h, mom):
        """Filter the effective stress (xx, yy, zz, xy; 3D also yz, zx) of particles
        0..n_owned-1 in place with the same zeroth-order Shepard sum as Eq. (46): the stress
        regularisation the paper points to for this noise (its ref. [14], there with MLS,
        `mls_stress`). The odd-even mode of sigma' is invisible to the pair-symmetric
        divergence of Eq. (26), so nothing else damps it. Wall ghosts carry the mirrored
        stress.

        Parameters
        ----------
        n_total, n_owned, x, vol, cells, h
            as `shepard_pressure`.
        stress : (cap, 4) or (cap, 6) float64 array
            effective stress (Pa), filtered in place.
        mom : (>= n_owned, 1 + the stress's columns) float64 array
            scratch.
        """
        moments(n_owned, x, stress, vol, cells.cell_start, cells.order, cells.ncell, h, False,
                mom)
        for i in range(n_owned):
            if mom[i, 0] > 0.0:
                for c in range(n_stress):
                    stress[i, c] = mom[i, 1 + c] / mom[i, 0]

    @nb.njit(cache=True)
    def mls_stress(n_total, n_owned, x, stress, vol, cells, h, mom):
        """Filter the effective stress of particles 0..n_owned-1 in place with the
        first-order moving-least-squares kernel, the stress regularisation of the paper's
        ref. [14] (Section 3.5.2):

            sigma_i <- sum_j V_j W_ij (beta_i . q_ij) sigma_j,   q_ij = (1, x_j - x_i),
            A_i beta_i = e_1,   A_i = sum_j V_j W_ij q_ij q_ij^T   (i included).

        It reproduces linear fields exactly, also where the support is cut: the
        zeroth-order Shepard sum pulls a free-surface particle's stress toward its interior
        neighbours', away from what its own strain carries, while Eq. (24) keeps
        integrating the strain into the porosity (n drifts to 0 at a slope face). Where
        A_i is nearly singular (too few neighbours off a line, or off a plane in 3D) it
        falls back to Shepard.

        Parameters
        ----------
        n_total, n_owned, x, vol, cells, h
            as `shepard_pressure`.
        stress : (cap, 4) or (cap, 6) float64 array
            effective stress (Pa), filtered in place.
        mom : (>= n_owned, `moment_width(dim, True, columns)`) float64 array
            scratch.
        """
        moments(n_owned, x, stress, vol, cells.cell_start, cells.order, cells.ncell, h, True,
                mom)
        for i in range(n_owned):
            r = mom[i]
            if dim == 2:
                a00, a01, a02, a11, a12, a22 = r[0], r[1], r[2], r[3], r[4], r[5]
                # beta = A^-1 e1: the first column of the inverse (cofactors / det)
                q0 = a11 * a22 - a12 * a12
                q1 = a02 * a12 - a01 * a22
                q2 = a01 * a12 - a02 * a11
                det = a00 * q0 + a01 * q1 + a02 * q2
                # scale-free test: det against the product of the diagonal
                if a00 > 0.0 and abs(det) > 1e-6 * a00 * a11 * a22:
                    b0, b1, b2 = q0 / det, q1 / det, q2 / det
                elif a00 > 0.0:
                    b0, b1, b2 = 1.0 / a00, 0.0, 0.0
                else:
                    continue
                for c in range(n_stress):
                    stress[i, c] = b0 * r[6 + 3 * c] + b1 * r[7 + 3 * c] + b2 * r[8 + 3 * c]
            else:
                ok, b0, b1, b2, b3 = first_column_4(r)
                if not ok:
                    if r[0] > 0.0:
                        b0, b1, b2, b3 = 1.0 / r[0], 0.0, 0.0, 0.0
                    else:
                        continue
                for c in range(n_stress):
                    k = 10 + 4 * c
                    stress[i, c] = (b0 * r[k] + b1 * r[k + 1] + b2 * r[k + 2]
                                    + b3 * r[k + 3])

    return shepard_pressure, shepard_stress, mls_stress


@nb.njit(cache=True, inline="always")
def first_column_4(r):
    """The first column b of the inverse of a symmetric 4x4 matrix A (A b = e1), by
    cofactors of the first row.

    Parameters
    ----------
    r : float64 array
        r[0:10] is A's upper triangle (00 01 02 03 11 12 13 22 23 33).

    Returns
    -------
    ok : bool
        False where A is nearly singular (det against the product of the diagonal,
        scale-free as in 2D) or A_00 <= 0.
    b0, b1, b2, b3 : float
        b (0 where not ok).
    """
    a00, a01, a02, a03 = r[0], r[1], r[2], r[3]
    a11, a12, a13, a22, a23, a33 = r[4], r[5], r[6], r[7], r[8], r[9]
    # 2x2 minors of rows 2-3 (columns j, k), then the cofactors C_0j of the first row
    m23_23 = a22 * a33 - a23 * a23
    m23_13 = a12 * a33 - a13 * a23
    m23_12 = a12 * a23 - a13 * a22
    m23_03 = a02 * a33 - a03 * a23
    m23_02 = a02 * a23 - a03 * a22
    m23_01 = a02 * a13 - a03 * a12
    c0 = a11 * m23_23 - a12 * m23_13 + a13 * m23_12
    c1 = -(a01 * m23_23 - a12 * m23_03 + a13 * m23_02)
    c2 = a01 * m23_13 - a11 * m23_03 + a13 * m23_01
    c3 = -(a01 * m23_12 - a11 * m23_02 + a12 * m23_01)
    det = a00 * c0 + a01 * c1 + a02 * c2 + a03 * c3
    if not (a00 > 0.0 and abs(det) > 1e-6 * a00 * a11 * a22 * a33):
        return False, 0.0, 0.0, 0.0, 0.0
    return True, c0 / det, c1 / det, c2 / det, c3 / det


shepard_pressure, shepard_stress, mls_stress = make_filters(2)
shepard_pressure_3d, shepard_stress_3d, mls_stress_3d = make_filters(3)

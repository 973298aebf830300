"""Particle shifting: keep the particle arrangement regular where the soil deforms.

The pair-symmetric momentum Eq. (26) of Lian et al. (2023) carries, for the pore pressure,
the term -2 p_i S_i / rho_i with S_i = sum_j V_j grad_i W_ij, the gradient of the particle
concentration C_i = sum_j V_j W_ij. On an even arrangement S_i = 0; in a disordered layer
(the base of a spreading debris, where particles sink between their neighbours) it is not,
and a particle there holds its place with a pressure its neighbours do not have (2.6x its
neighbours' at the base of the retrogressive slope). The pressure differences alone,
without that term, are unstable at free corners (`update.pore_pressure_force`), so the
arrangement is kept even instead, as incompressible SPH does (Lind et al. 2012,
J. Comput. Phys. 231; Skillen et al. 2013, CMAME 265): each step every particle moves by

    delta r_i = -D grad C_i,   D = A h^2 |L_i| dt,

down the concentration gradient, by at most `cap` (a fraction of dx). |L_i| is the norm
of the particle's velocity gradient (sums 4-7 of `pair_sums`): disorder is made by
deformation, so soil at rest or in rigid motion does not shift, and the bottom row under a
debris sliding on a no-slip base does (there |v| is small, and a shift scaled with |v|,
as Skillen et al.'s, leaves the basal layer as disordered as without it). Near a free
surface S_i points into the soil because the support is cut, not because the particles are
uneven, so by the trace of the moment matrix of Eq. (22) (1.98 inside, 1.92 on the second
row and 1.28 on the surface row of a lattice at h = 1.2 dx): below `free_trace` (the free
surface of the ponding condition) a particle does not shift; below `surface_trace` only
the part along the surface is kept (shifting the surface row along its tangent too lifts
the debris front of the slope off the floor, particle by particle, until one compacts to
n = 0). The particle's fields (stress, porosity, pressure, plastic strain,
displacement) stay with it: the shift is a small fraction of dx per step, an error of the
order of delta r . grad f.

In 3D (`shift_particles_3d`) the same with the 3D layout of the sums (M: 9 columns, L: 9).
The free surface is the ponding condition's (`free_surface.on_free_surface`: M's trace
plus its smallest eigenvalue, halved, below 1.5). The band below it uses the trace of a
3D lattice:
2.05 on the surface row, 2.90 on the second and 2.945 inside at h = 1.2 dx (2.03 / 2.875
/ 2.98 at 1.3 dx), so `SURFACE_TRACE_3D` = 2.92. Under a face M has
one small eigenvalue, whose eigenvector is the face's normal, and the shift loses its part
along it; under an edge two, and the shift keeps only its part along the edge (the
largest eigenvalue's eigenvector); at a corner none is kept.
"""

import math

import numba as nb

from psph.kernels.free_surface import FREE_SURFACE, eigenvalues_3d, on_free_surface
from psph.kernels.sum_columns import sum_layout

SHIFT_CAP = 0.05  # the longest shift of one step, in dx
SURFACE_TRACE = 1.95  # trace(M) below which only the part along the surface is kept
FREE_TRACE = FREE_SURFACE  # trace(M) below which a particle is on the free surface: no shift
SURFACE_TRACE_3D = 2.92  # SURFACE_TRACE in 3D (module docstring)
# M's two smallest eigenvalues closer than this share of its trace: an edge (module
# docstring). A lattice's row under a face has a gap of 0.040 / 2.90 = 1.4 %; under an
# edge 0 (0.939, 0.939, 0.978 at h = 1.2 dx); jitter moves them by less than the half
EDGE_GAP_3D = 0.007


@nb.njit(cache=True)
def _surface_normal(m00, m01, m10, m11):
    """Unit eigenvector of the symmetric part of the moment matrix for its smaller
    eigenvalue: the direction in which the support is cut."""
    b = 0.5 * (m01 + m10)
    lam = 0.5 * (m00 + m11) - math.sqrt(0.25 * (m00 - m11) ** 2 + b * b)
    n0 = b
    n1 = lam - m00
    if abs(n0) + abs(n1) < 1e-12 * (abs(m00) + abs(m11)):
        n0 = lam - m11
        n1 = b
    norm = math.hypot(n0, n1)
    if norm == 0.0:
        return 0.0, 0.0
    return n0 / norm, n1 / norm


@nb.njit(cache=True)
def shift_particles(n_owned, grad_c, sums, coef, h, dt, cap, surface_trace, free_trace, x,
                    shift):
    """Move owned particles by delta r_i = -A h^2 |L_i| dt grad C_i (module docstring), at
    most `cap` long; not at all where trace(M_i) < free_trace, only along the surface
    where trace(M_i) < surface_trace.

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    grad_c : (cap, 2) float64 array
        concentration gradient grad C_i (1/m).
    sums : (cap, nsums) float64 array
        the sums of `pair_sums`: M_i in columns 0-3, L_i (1/s) in columns 4-7.
    coef : float
        A (dimensionless).
    h : float
        smoothing length (m).
    dt : float
        time step (s).
    cap : float
        the longest shift (m).
    surface_trace, free_trace : float
        the thresholds of trace(M_i) (dimensionless).
    x : (cap, 2) float64 array
        positions (m), moved in place.
    shift : (cap, 2) float64 array
        receives the shifts (m).
    """
    for i in range(n_owned):
        m = sums[i]
        trace = m[0] + m[3]
        if trace < free_trace:
            shift[i, 0] = 0.0
            shift[i, 1] = 0.0
            continue
        rate = math.sqrt(m[4] * m[4] + m[5] * m[5] + m[6] * m[6] + m[7] * m[7])
        d = coef * h * h * rate * dt
        d0 = -d * grad_c[i, 0]
        d1 = -d * grad_c[i, 1]
        if trace < surface_trace:
            n0, n1 = _surface_normal(m[0], m[1], m[2], m[3])
            dn = d0 * n0 + d1 * n1
            d0 -= dn * n0
            d1 -= dn * n1
        length = math.hypot(d0, d1)
        if length > cap:
            d0 *= cap / length
            d1 *= cap / length
        x[i, 0] += d0
        x[i, 1] += d1
        shift[i, 0] = d0
        shift[i, 1] = d1


@nb.njit(cache=True, inline="always")
def _eigenvector_3d(a00, a01, a02, a11, a12, a22, lam):
    """Unit eigenvector of the symmetric 3x3 matrix A for its (simple) eigenvalue lam: the
    largest cross product of two rows of A - lam I; (0, 0, 0) if there is none."""
    best = 0.0
    n0 = n1 = n2 = 0.0
    for k in range(3):  # the row pairs (0, 1), (0, 2), (1, 2)
        if k == 0:
            u0, u1, u2, v0, v1, v2 = a00 - lam, a01, a02, a01, a11 - lam, a12
        elif k == 1:
            u0, u1, u2, v0, v1, v2 = a00 - lam, a01, a02, a02, a12, a22 - lam
        else:
            u0, u1, u2, v0, v1, v2 = a01, a11 - lam, a12, a02, a12, a22 - lam
        c0 = u1 * v2 - u2 * v1
        c1 = u2 * v0 - u0 * v2
        c2 = u0 * v1 - u1 * v0
        size = c0 * c0 + c1 * c1 + c2 * c2
        if size > best:
            best, n0, n1, n2 = size, c0, c1, c2
    if best == 0.0:
        return 0.0, 0.0, 0.0
    norm = math.sqrt(best)
    return n0 / norm, n1 / norm, n2 / norm


@nb.njit(cache=True)
def _surface_normal_3d(a00, a01, a02, a11, a12, a22):
    """Unit eigenvector of the symmetric 3x3 matrix A for its smallest eigenvalue: the
    direction in which the support is cut; (0, 0, 0) where A is isotropic."""
    l1, _, l3 = eigenvalues_3d(a00, a01, a02, a11, a12, a22)
    if l3 - l1 <= 1e-15 * abs(l3):
        return 0.0, 0.0, 0.0
    return _eigenvector_3d(a00, a01, a02, a11, a12, a22, l1)


@nb.njit(cache=True)
def _along_surface_3d(d0, d1, d2, a00, a01, a02, a11, a12, a22, edge_gap):
    """The part of the shift (d0, d1, d2) along the surface whose cut directions M
    (upper triangle a..) shows: on a face (one small eigenvalue) the shift less its part
    along that eigenvector; along an edge (the two smallest within `edge_gap` of each
    other: cut along both faces' normals) only its part along the largest eigenvector,
    the edge; at a corner or where M is isotropic, nothing."""
    l1, l2, l3 = eigenvalues_3d(a00, a01, a02, a11, a12, a22)
    if l3 - l1 <= edge_gap:
        return 0.0, 0.0, 0.0
    if l2 - l1 > edge_gap:  # a face
        n0, n1, n2 = _eigenvector_3d(a00, a01, a02, a11, a12, a22, l1)
        dn = d0 * n0 + d1 * n1 + d2 * n2
        return d0 - dn * n0, d1 - dn * n1, d2 - dn * n2
    e0, e1, e2 = _eigenvector_3d(a00, a01, a02, a11, a12, a22, l3)  # an edge
    de = d0 * e0 + d1 * e1 + d2 * e2
    return de * e0, de * e1, de * e2


M_3D = sum_layout(3).M  # the 3D layout's first columns of M and of the velocity sums
GV_3D = sum_layout(3).GV


@nb.njit(cache=True)
def shift_particles_3d(n_owned, grad_c, sums, coef, h, dt, cap, surface_trace, x, shift):
    """`shift_particles` in 3D: M_i and L_i from the 3D layout of `sums`
    (`sum_columns.sum_layout(3)`); no shift on the free surface of
    `free_surface.on_free_surface`.

    Parameters
    ----------
    n_owned, coef, h, dt, cap
        as `shift_particles`.
    grad_c : (cap, 3) float64 array
        concentration gradient (1/m).
    sums : (cap, nsums) float64 array
        the 3D pair sums.
    surface_trace : float
        trace(M_i) below which only the part along the surface is kept.
    x : (cap, 3) float64 array
        positions (m), moved in place.
    shift : (cap, 3) float64 array
        receives the shifts (m).
    """
    cm = M_3D
    cgv = GV_3D
    for i in range(n_owned):
        m = sums[i]
        trace = m[cm] + m[cm + 4] + m[cm + 8]
        if on_free_surface(m, cm, 3):
            for k in range(3):
                shift[i, k] = 0.0
            continue
        rate = 0.0
        for k in range(9):
            rate += m[cgv + k] * m[cgv + k]
        d = coef * h * h * math.sqrt(rate) * dt
        d0 = -d * grad_c[i, 0]
        d1 = -d * grad_c[i, 1]
        d2 = -d * grad_c[i, 2]
        if trace < surface_trace:
            d0, d1, d2 = _along_surface_3d(
                d0, d1, d2, m[cm], 0.5 * (m[cm + 1] + m[cm + 3]),
                0.5 * (m[cm + 2] + m[cm + 6]), m[cm + 4], 0.5 * (m[cm + 5] + m[cm + 7]),
                m[cm + 8], EDGE_GAP_3D * trace)
        length = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if length > cap:
            d0 *= cap / length
            d1 *= cap / length
            d2 *= cap / length
        x[i, 0] += d0
        x[i, 1] += d1
        x[i, 2] += d2
        shift[i, 0] = d0
        shift[i, 1] = d1
        shift[i, 2] = d2

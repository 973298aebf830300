"""The free surface: where a particle's kernel support is cut, read from the moment matrix
M = sum_j V_j x_ji (x) grad_i W_ij of Eq. (22), which is the identity where the support is
full. A particle is on the free surface when, in 2D, trace(M) < FREE_SURFACE = 1.5 (its
support less than 3/4 full), and in 3D when M's smallest eigenvalue plus the mean of the
other two is below the same 1.5. The ponding and drained conditions hold its pore
pressure there (`update.make_advance`, `projection.imposed_increments`), and particle
shifting leaves it where it is (`shifting`).

Why not the trace in 3D as well: under a plane face M has one small eigenvalue, along the
face's normal, and dim - 1 larger ones along the face. The 2D trace is the normal's plus
the tangent's; the 3D trace (say trace < 2.25, 3/4 of 3) would give the tangents twice
the normal's weight, so that a tangent fuller or emptier than a lattice's (a compressed
toe, a thin sheet) moves the test. The normal plus the tangents' mean, (trace + l1) / 2,
weighs them as the 2D trace does. On a lattice at h = 1.2 dx it agrees with the 2D test
row by row: a face 1.281 in 2D and 1.271 in 3D, the row below 1.921 and 1.921, an edge
0.786 and 0.845, a 3D corner 0.579 (`tests/test_kernels_3d.py -k free_surface`).

The smallest eigenvalue is the normal's on a face. Under an edge or at a corner the
normal is not one direction, but there every test flags the particle by a wide margin.
The two smallest eigenvalues summed are the normal and the emptier tangent: they flag
more of a compressed toe than the 2D test does (docs/vv/collapse_saturated_3d.md, "The
drained surface in 3D").
"""

import math

import numba as nb

FREE_SURFACE = 1.5  # trace(M) in 2D, (trace(M) + its smallest eigenvalue) / 2 in 3D


@nb.njit(cache=True)
def eigenvalues_3d(a00, a01, a02, a11, a12, a22):
    """The eigenvalues of a symmetric 3x3 matrix A, by the trigonometric solution of the
    characteristic cubic.

    Parameters
    ----------
    a00, a01, a02, a11, a12, a22 : float
        the upper triangle of A (any unit; M of Eq. (22) is dimensionless).

    Returns
    -------
    l1, l2, l3 : float
        the eigenvalues, l1 <= l2 <= l3.
    """
    q = (a00 + a11 + a22) / 3.0
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    p2 = (a00 - q) ** 2 + (a11 - q) ** 2 + (a22 - q) ** 2 + 2.0 * p1
    if p2 <= 1e-30 * q * q:
        return q, q, q
    pp = math.sqrt(p2 / 6.0)
    b00, b11, b22 = (a00 - q) / pp, (a11 - q) / pp, (a22 - q) / pp
    b01, b02, b12 = a01 / pp, a02 / pp, a12 / pp
    r = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02)
               + b02 * (b01 * b12 - b11 * b02))
    r = min(1.0, max(-1.0, r))
    phi = math.acos(r) / 3.0
    l3 = q + 2.0 * pp * math.cos(phi)
    l1 = q + 2.0 * pp * math.cos(phi + 2.0 * math.pi / 3.0)
    return l1, 3.0 * q - l1 - l3, l3


@nb.njit(cache=True)
def on_free_surface(m, cm: int, dim: int) -> bool:
    """Whether a particle is on the free surface (the test of the module docstring).

    Parameters
    ----------
    m : (nsums,) float64 array
        the particle's row of the pair sums.
    cm : int
        first column of M (dim x dim, row-major, dimensionless).
    dim : int
        2 or 3.

    Returns
    -------
    bool
    """
    if dim == 2:
        return m[cm] + m[cm + 3] < FREE_SURFACE
    a00, a11, a22 = m[cm], m[cm + 4], m[cm + 8]
    a01 = 0.5 * (m[cm + 1] + m[cm + 3])
    a02 = 0.5 * (m[cm + 2] + m[cm + 6])
    a12 = 0.5 * (m[cm + 5] + m[cm + 7])
    trace = a00 + a11 + a22
    # l1 is at least the smallest diagonal less its row's off-diagonals (Gershgorin):
    # inside the soil that bound already settles it, without the cubic
    least = min(a00 - abs(a01) - abs(a02), a11 - abs(a01) - abs(a12),
                a22 - abs(a02) - abs(a12))
    if 0.5 * (trace + least) >= FREE_SURFACE:
        return False
    l1, _, _ = eigenvalues_3d(a00, a01, a02, a11, a12, a22)
    return 0.5 * (trace + l1) < FREE_SURFACE

"""Lattice sums of the pair terms of Eq. (26) that carry a stabilisation, in 2D and 3D, for
setting a 3D scene's stabilisation to a 2D scene's strength (the plane-strain checks).

    python bench/tools/lattice_sums.py 1.2 1.3 1.5 2    # M_f in 2D and 3D at these h / dx

The artificial stress of Eq. (26)'s C_ij (Gray, Monaghan & Swift 2001, the paper's refs.
[11, 18]) adds to a pair's stress sum f_ij^n (R_i + R_j), f_ij = W(r_ij) / W(dx), with
R = -epsilon times the tensile principal effective stresses
(`psph/kernels/artificial_stress.py`). For a smooth R on the lattice the
pair sum sum_j V_j f^n (R_i + R_j) grad_i W_ij / rho is, to first order, M_f . grad R /
rho with the moment M_f = sum_j V_j f^n x_ji (x) grad_i W_ij (the sum with R_i cancels
on a symmetric lattice): a stress of its own that does not vanish as dx falls, and whose
moment depends on the dimension at one h / dx. At h = 1.2 dx and n = 2.55 M_f is 0.520
on the square lattice and 0.319 on the cubic one, so at one epsilon a 3D lattice (a slab
of y-layers carrying a 2D field, `collapse_saturated_3d`, among them) has 0.61 of the 2D
lattice's artificial stress.
"""

import itertools

import numpy as np

from psph.kernels.spline import dw_cubic_dim, w_cubic_dim


def artificial_stress_moment(dim: int, h_factor: float, n: float) -> float:
    """M_f's diagonal (xx) on the square (dim 2) or cubic (3) lattice of spacing dx = 1 with
    h = h_factor: sum over the lattice points x_j within 2h of the origin of
    (W(r) / W(1))^n x_j,0^2 (-dW/dr) / r."""
    h = h_factor
    w_dx = w_cubic_dim(1.0, h, dim)
    reach = int(np.ceil(2 * h))
    m = 0.0
    for idx in itertools.product(range(-reach, reach + 1), repeat=dim):
        r = float(np.linalg.norm(idx))
        if r == 0.0 or r >= 2 * h:
            continue
        f = (w_cubic_dim(r, h, dim) / w_dx) ** n
        m += f * idx[0] * idx[0] * (-dw_cubic_dim(r, h, dim)) / r
    return m


def artificial_stress_3d_over_2d(h_factor: float, n: float) -> float:
    """The 3D lattice's artificial stress over the 2D lattice's at one epsilon."""
    return artificial_stress_moment(3, h_factor, n) / artificial_stress_moment(2, h_factor, n)


if __name__ == "__main__":
    import sys

    for hf in [float(a) for a in sys.argv[1:]] or [1.2]:
        m2, m3 = artificial_stress_moment(2, hf, 2.55), artificial_stress_moment(3, hf, 2.55)
        print(f"h = {hf:g} dx, n = 2.55: M_f 2D {m2:.3f}, 3D {m3:.3f}, 3D / 2D {m3 / m2:.3f}")

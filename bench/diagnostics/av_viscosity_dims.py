"""How strong Monaghan's artificial viscosity is in 3D against 2D at the same alpha.

    python bench/diagnostics/av_viscosity_dims.py            # h = 1.2 dx (the 3D scenes)
    python bench/diagnostics/av_viscosity_dims.py --h-factor 1.3 2 3 4

The viscous term of the momentum equation (Eq. 26's C_ij, `interactions.make_pair_sums`),
a_i = -sum_j m_j Pi_ij grad_i W_ij with Pi_ij = -alpha c mu_ij / rho_ij and
mu_ij = h v_ij . x_ij / (r_ij^2 + 0.01 h^2) for approaching pairs, acts in the continuum
as a kinematic viscosity nu = alpha h c / (2 (d + 2)) (Monaghan 2005, Rep. Prog. Phys.
68, Section 4.1): alpha h c / 8 in 2D, alpha h c / 10 in 3D. A slab between mirror
walls (`collapse_saturated_3d`) is a 3D lattice that carries a 2D flow, so at the 2D
scene's alpha it has a weaker viscosity than the 2D scene.

This script sums the viscous acceleration of one particle of a square (cubic) lattice of
spacing dx in the shear flow v_x = cos(k z), k dx = 0.02 (a long wave: the lattice's
value of nu), over the 2D lattice and over the 3D lattice whose y-layers all carry the
flow (the slab with its mirror ghosts), with the cubic spline of `psph.kernels.spline`,
and prints nu(3D) / nu(2D): 0.860 at h = 1.2 dx, 0.828 at 1.3 dx, tending to 8 / 10 for
large h / dx. `equivalent_av_alpha` is its inverse: the alpha that gives a slab the 2D
scene's viscosity at alpha = 1.
"""

import argparse
import itertools

import numpy as np

from psph.kernels.spline import dw_cubic_dim


def viscous_acceleration(dim: int, h_factor: float, k: float = 0.02) -> float:
    """x-acceleration / (alpha c) of a lattice particle (dx = 1, rho = 1) at z = 0 in the
    shear flow v_x = cos(k z), summed over the lattice points within 2h."""
    h = h_factor
    reach = int(np.ceil(2 * h))
    a = 0.0
    for idx in itertools.product(range(-reach, reach + 1), repeat=dim):
        xb = np.array(idx, float)
        r = float(np.linalg.norm(xb))
        if r == 0.0 or r >= 2 * h:
            continue
        v_ab = 1.0 - np.cos(k * xb[-1])  # v_a - v_b along x
        x_ab0 = -xb[0]
        vdotr = v_ab * x_ab0
        if vdotr >= 0.0:  # Monaghan's switch: approaching pairs only
            continue
        mu = h * vdotr / (r * r + 0.01 * h * h)
        a -= mu * dw_cubic_dim(r, h, dim) * x_ab0 / r  # -m Pi grad W with Pi = -mu
    return a / (k * k)


def viscosity_ratio(h_factor: float) -> float:
    """nu of the 3D lattice over nu of the 2D lattice, at the same alpha and h / dx."""
    return viscous_acceleration(3, h_factor) / viscous_acceleration(2, h_factor)


def equivalent_av_alpha(h_factor: float, alpha_2d: float = 1.0) -> float:
    """The 3D alpha whose lattice viscosity is that of the 2D scene's `alpha_2d`."""
    return alpha_2d / viscosity_ratio(h_factor)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--h-factor", type=float, nargs="*", default=[1.2])
    args = ap.parse_args()
    print(f"{'h / dx':>7s} {'nu 3D / nu 2D':>14s} {'3D alpha for 2D alpha = 1':>26s}")
    for hf in args.h_factor:
        print(f"{hf:7.2f} {viscosity_ratio(hf):14.4f} {equivalent_av_alpha(hf):26.4f}")


if __name__ == "__main__":
    main()

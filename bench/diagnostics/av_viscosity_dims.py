"""How strong Monaghan's artificial viscosity is in 3D against 2D at the same alpha.

    python bench/diagnostics/av_viscosity_dims.py            # h = 1.2 dx (the 3D scenes)
    python bench/diagnostics/av_viscosity_dims.py --h-factor 1.3 2 3 4
    python bench/diagnostics/av_viscosity_dims.py --floor   # a floor's ghosts on its rows

The viscous term of the momentum equation (Eq. 26's C_ij, `interactions.make_pair_sums`),
a_i = -sum_j m_j Pi_ij grad_i W_ij with Pi_ij = -alpha c mu_ij / rho_ij and
mu_ij = h v_ij . x_ij / (r_ij^2 + 0.01 h^2), applied to every pair acts in the continuum
as a kinematic viscosity nu = alpha h c / (2 (d + 2)) (Monaghan 2005, Rep. Prog. Phys.
68): alpha h c / 8 in 2D, alpha h c / 10 in 3D. psph applies it to approaching pairs
only (v_ij . x_ij < 0), which in a shear flow keeps about half of it in either
dimension; the ratio of the two is what this script measures. A slab between mirror
walls (`collapse_saturated_3d`) is a 3D lattice that carries a 2D flow (its wall ghosts
keep the viscosity because the scene is coupled), so at the 2D scene's alpha it has a
weaker viscosity than the 2D scene.

This script sums the viscosity of one particle of a square (cubic) lattice of spacing
dx in a long wave (k dx = 0.02: the lattice's value), over the 2D lattice and over the
3D lattice whose y-layers all carry the flow, with the cubic spline of
`psph.kernels.spline`, for a shear wave v_x = cos(k z) and a longitudinal one
v_x = cos(k x), and prints nu(3D) / nu(2D): 0.860 (shear) and 0.809 (longitudinal) at
h = 1.2 dx, approaching 8 / 10 for large h / dx (0.803 at 6 dx: the 0.01 h^2 term).
Its inverse is the 3D alpha that gives the 2D scene's viscosity at alpha = 1: 1.16 for
shear, 1.24 for the longitudinal wave at h = 1.2 dx, 5 / 4 in the continuum.
"""

import argparse
import itertools

import numpy as np

from psph.kernels.spline import dw_cubic_dim


def lattice_viscosity(dim: int, h_factor: float, wave: str = "shear",
                      k: float = 0.02) -> float:
    """nu / (alpha c dx) of the lattice (dx = 1, rho = 1, m = 1) from the viscous
    acceleration a_x = -sum_j m_j Pi_ij d_x W_ij of the particle at the origin in the
    wave v_x = cos(k z) ("shear", z the last axis) or cos(k x) ("longitudinal"), where
    a_x = -nu k^2: the sum over the lattice points within 2h, approaching pairs only."""
    h = h_factor
    reach = int(np.ceil(2 * h))
    a = 0.0
    for idx in itertools.product(range(-reach, reach + 1), repeat=dim):
        xb = np.array(idx, float)
        r = float(np.linalg.norm(xb))
        if r == 0.0 or r >= 2 * h:
            continue
        v_ab = 1.0 - np.cos(k * (xb[-1] if wave == "shear" else xb[0]))  # v_a - v_b, x
        x_ab0 = -xb[0]
        vdotr = v_ab * x_ab0
        if vdotr >= 0.0:  # Monaghan's switch: approaching pairs only
            continue
        mu = h * vdotr / (r * r + 0.01 * h * h)
        pi_ab = -mu  # -alpha c mu / rho with alpha c = rho = 1
        a -= pi_ab * dw_cubic_dim(r, h, dim) * x_ab0 / r  # -m Pi grad_a W, x component
    return -a / (k * k)


def floor_dashpot(dim: int, h_factor: float, row: int) -> float:
    """The wall-normal dashpot of a floor's mirror ghosts on the particle of lattice row
    `row` (at z = row + 1/2 above the floor z = 0, dx = 1): its viscous acceleration a_z
    per unit speed toward the floor, from its pairs with the ghosts (the mirror images of
    the lattice's points below the floor, moving away from it at the same speed, so
    each pair approaches at twice the speed; v_slip on ghost pairs has no tangential
    part to add), alpha c = rho = m = 1. The real rows move together and add nothing."""
    h = h_factor
    reach = int(np.ceil(2 * h))
    za = row + 0.5
    a = 0.0
    for idx in itertools.product(range(-reach, reach + 1), repeat=dim - 1):
        for k in range(reach + 1):
            x_ab = np.array([-i for i in idx] + [za + k + 0.5])  # x_a - x_ghost
            r = float(np.linalg.norm(x_ab))
            if r >= 2 * h:
                continue
            vdotr = -2.0 * x_ab[-1]  # v_a - v_b = -2 along z: approaching
            mu = h * vdotr / (r * r + 0.01 * h * h)
            a += mu * dw_cubic_dim(r, h, dim) * x_ab[-1] / r  # -m Pi grad_a W, z
    return a


def viscosity_ratio(h_factor: float, wave: str = "shear") -> float:
    """nu of the 3D lattice over nu of the 2D lattice, at the same alpha and h / dx."""
    return lattice_viscosity(3, h_factor, wave) / lattice_viscosity(2, h_factor, wave)


def equivalent_av_alpha(h_factor: float, wave: str = "shear", alpha_2d: float = 1.0) -> float:
    """The 3D alpha whose lattice viscosity is that of the 2D scene's `alpha_2d`."""
    return alpha_2d / viscosity_ratio(h_factor, wave)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--h-factor", type=float, nargs="*", default=[1.2])
    ap.add_argument("--floor", action="store_true",
                    help="the floor ghosts' wall-normal dashpot on the bottom rows instead")
    args = ap.parse_args()
    if args.floor:
        print(f"{'h / dx':>7s} {'row':>4s} {'a_z 2D':>9s} {'a_z 3D':>9s} {'3D / 2D':>8s} "
              f"{'x 5/4':>7s}   (per unit speed toward the floor, alpha c = rho = dx = 1)")
        for hf in args.h_factor:
            for row in range(int(np.ceil(2 * hf))):
                f2, f3 = floor_dashpot(2, hf, row), floor_dashpot(3, hf, row)
                if f2 == 0.0 and f3 == 0.0:
                    continue
                print(f"{hf:7.2f} {row:4d} {f2:9.4f} {f3:9.4f} {f3 / f2:8.4f} "
                      f"{1.25 * f3 / f2:7.4f}")
        return
    print(f"{'h / dx':>7s} {'wave':>13s} {'nu 2D':>8s} {'nu 3D':>8s} {'3D / 2D':>8s} "
          f"{'3D alpha for 2D alpha = 1':>26s}   (nu / (alpha c dx))")
    for hf in args.h_factor:
        for wave in ("shear", "longitudinal"):
            n2, n3 = lattice_viscosity(2, hf, wave), lattice_viscosity(3, hf, wave)
            print(f"{hf:7.2f} {wave:>13s} {n2:8.4f} {n3:8.4f} {n3 / n2:8.4f} "
                  f"{n2 / n3:26.4f}")


if __name__ == "__main__":
    main()

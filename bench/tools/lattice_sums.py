"""Lattice sums of the pair terms of Eq. (26) that carry a stabilisation, in 2D and 3D, for
setting a 3D scene's stabilisation to a 2D scene's strength (the plane-strain checks).

    python bench/tools/lattice_sums.py 1.2 1.3 1.5 2    # M_f in 2D and 3D at these h / dx
    python bench/tools/lattice_sums.py --viscosity 1.2 1.3 2 3 4 6   # the viscosity's ratio
    python bench/tools/lattice_sums.py --floor 1.2 1.3  # a floor's ghosts on its rows
    python bench/tools/lattice_sums.py --quick          # both sums at h = 1.2 dx

Each prints its table and writes it to <out>/lattice_sums[-viscosity|-floor].json.

The artificial stress of Eq. (26)'s C_ij (Gray, Monaghan & Swift 2001, the paper's
refs. [11, 18]) adds to a pair's stress sum f_ij^n (R_i + R_j), f_ij = W(r_ij) / W(dx), with
R = -epsilon times the tensile principal effective stresses
(`psph/kernels/artificial_stress.py`). For a smooth R on the lattice the
pair sum sum_j V_j f^n (R_i + R_j) grad_i W_ij / rho is, to first order, M_f . grad R /
rho with the moment M_f = sum_j V_j f^n x_ji (x) grad_i W_ij (the sum with R_i cancels
on a symmetric lattice): a stress of its own that does not vanish as dx falls, and whose
moment depends on the dimension at one h / dx. At h = 1.2 dx and n = 2.55 M_f is 0.520
on the square lattice and 0.319 on the cubic one, so at one epsilon a 3D lattice (a slab
of y-layers carrying a 2D field, `collapse_saturated_3d`, among them) has 0.61 of the 2D
lattice's artificial stress.

The artificial viscosity, the viscous term of the momentum equation (Eq. 26's C_ij,
`interactions.make_pair_sums`), a_i = -sum_j m_j Pi_ij grad_i W_ij with Pi_ij = -alpha c
mu_ij / rho_ij and mu_ij = h v_ij . x_ij / (r_ij^2 + 0.01 h^2), applied to every pair acts
in the continuum as a kinematic viscosity nu = alpha h c / (2 (d + 2)) (Monaghan 2005, Rep.
Prog. Phys. 68): alpha h c / 8 in 2D, alpha h c / 10 in 3D. psph applies it to approaching
pairs only (v_ij . x_ij < 0), which in a shear flow keeps about half of it in either
dimension; the ratio of the two is what `--viscosity` measures. A slab between mirror walls
(`collapse_saturated_3d`) is a 3D lattice that carries a 2D flow (its wall ghosts keep the
viscosity because the scene is coupled), so at the 2D scene's alpha it has a weaker
viscosity than the 2D scene.

`--viscosity` sums the viscosity of one particle of a square (cubic) lattice of spacing
dx in a long wave (k dx = 0.02: the lattice's value), over the 2D lattice and over the
3D lattice whose y-layers all carry the flow, with the cubic spline of
`psph.kernels.spline`, for a shear wave v_x = cos(k z) and a longitudinal one
v_x = cos(k x), and prints nu(3D) / nu(2D): 0.860 (shear) and 0.809 (longitudinal) at
h = 1.2 dx, approaching 8 / 10 for large h / dx (0.803 at 6 dx: the 0.01 h^2 term).
Its inverse is the 3D alpha that gives the 2D scene's viscosity at alpha = 1: 1.16 for
shear, 1.24 for the longitudinal wave at h = 1.2 dx, 5 / 4 in the continuum.

`--floor`: the wall-normal dashpot of a floor's mirror ghosts on the bottom rows, in 2D
and 3D.
"""

import argparse
import itertools
import json
from pathlib import Path

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


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("h_factor", type=float, nargs="*", default=[1.2], help="h / dx")
    kind = ap.add_mutually_exclusive_group()
    kind.add_argument("--viscosity", action="store_true",
                      help="the artificial viscosity's 3D / 2D ratio instead of M_f")
    kind.add_argument("--floor", action="store_true",
                      help="the floor ghosts' wall-normal dashpot on the bottom rows instead")
    kind.add_argument("--quick", action="store_true",
                      help="M_f and the viscosity's ratio at h = 1.2 dx (a smoke check)")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "out",
                    help="directory of the JSON table (default bench/out)")
    args = ap.parse_args(argv)
    rows = []
    if args.floor:
        print(f"{'h / dx':>7s} {'row':>4s} {'a_z 2D':>9s} {'a_z 3D':>9s} {'3D / 2D':>8s} "
              f"{'x 5/4':>7s}   (per unit speed toward the floor, alpha c = rho = dx = 1)")
        for hf in args.h_factor:
            for row in range(int(np.ceil(2 * hf))):
                f2, f3 = floor_dashpot(2, hf, row), floor_dashpot(3, hf, row)
                if f2 == 0.0 and f3 == 0.0:
                    continue
                rows.append({"h_factor": hf, "row": row, "a_z_2d": f2, "a_z_3d": f3})
                print(f"{hf:7.2f} {row:4d} {f2:9.4f} {f3:9.4f} {f3 / f2:8.4f} "
                      f"{1.25 * f3 / f2:7.4f}")
    if args.viscosity or args.quick:
        print(f"{'h / dx':>7s} {'wave':>13s} {'nu 2D':>8s} {'nu 3D':>8s} {'3D / 2D':>8s} "
              f"{'3D alpha for 2D alpha = 1':>26s}   (nu / (alpha c dx))")
        for hf in [1.2] if args.quick else args.h_factor:
            for wave in ("shear", "longitudinal"):
                n2, n3 = lattice_viscosity(2, hf, wave), lattice_viscosity(3, hf, wave)
                rows.append({"h_factor": hf, "wave": wave, "nu_2d": n2, "nu_3d": n3})
                print(f"{hf:7.2f} {wave:>13s} {n2:8.4f} {n3:8.4f} {n3 / n2:8.4f} "
                      f"{n2 / n3:26.4f}")
    if not (args.viscosity or args.floor):
        for hf in [1.2] if args.quick else args.h_factor:
            m2 = artificial_stress_moment(2, hf, 2.55)
            m3 = artificial_stress_moment(3, hf, 2.55)
            rows.append({"h_factor": hf, "n": 2.55, "M_f_2d": m2, "M_f_3d": m3})
            print(f"h = {hf:g} dx, n = 2.55: M_f 2D {m2:.3f}, 3D {m3:.3f}, "
                  f"3D / 2D {m3 / m2:.3f}")
    tag = "-floor" if args.floor else "-viscosity" if args.viscosity else ""
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / f"lattice_sums{tag}.json").write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()

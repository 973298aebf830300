"""What the fixed base under the Section 4.5 slope's face carries after the gravity
loading, and how close to the clay's peak strength that is.

Horizontal equilibrium of the soil right of a vertical section x = x_c through the crest:
the face is free and drained (p = 0 on it, the water table at the ground surface of
Section 4.5), so the section's total horizontal thrust, its effective part -∫σ'_xx dz and
its water part ∫p dz, is carried by the shear of the base alone. With the water table at
the surface the water's part is ρ_l g H² / 2 (1.96 MN/m for the 20 m slope) whatever the
soil does, and the 27° face spreads it over a base of H / tan 27° = 39 m: 50 kPa of
average shear from the water alone, against the clay's peak cohesion of 55 kPa.

The strength ratio of a stress is √J2 / (κ − ξ I1) of the Drucker–Prager surface
Eq. (14) with the plane-strain constants Eq. (16): 1 on the surface, above 1 beyond it.

    python -m psph.verify.slope_statics RUN --crest 141.5 --dx 1.0

reads snapshot 0 (the state after `initial.equilibrate`) of the 2D run RUN.
"""

import argparse
import math
from pathlib import Path

import h5py
import numpy as np

from psph.kernels.plasticity import dp_constants


def strength_ratio(stress: np.ndarray, phi_deg: float, c: float) -> np.ndarray:
    """√J2 / (κ − ξ I1) of each effective stress (n, 6) (Voigt xx, yy, zz, xy, yz, zx,
    tension positive) against the Drucker–Prager surface Eq. (14), (16) of friction angle
    phi_deg and cohesion c (Pa)."""
    xi, kappa = dp_constants(math.radians(phi_deg), c)
    i1 = stress[:, :3].sum(axis=1)
    dev = stress[:, :3] - (i1 / 3.0)[:, None]
    j2 = 0.5 * (dev ** 2).sum(axis=1) + (stress[:, 3:] ** 2).sum(axis=1)
    return np.sqrt(j2) / (kappa - xi * i1)


def base_statics(x: np.ndarray, stress: np.ndarray, p: np.ndarray, dx: float, crest: float,
                 phi_deg: float, c: float) -> dict:
    """The horizontal balance of the soil right of the particle column at `crest` and the
    strength ratios, for a 2D lattice of spacing dx standing on a base at the lowest row.

    Returns the thrust on the column (effective, water, total; N/m), the shear the bottom
    row right of it carries (N/m; σ_xy summed times dx) and the base length, the largest
    strength ratio in the bottom row and above the third row, and where they are."""
    col = np.abs(x[:, 0] - crest) < 0.5 * dx
    effective = float(-(stress[col, 0]).sum() * dx)
    water = float(p[col].sum() * dx)
    bottom = x[:, 1] < x[:, 1].min() + 0.25 * dx
    right = bottom & (x[:, 0] > crest + 0.5 * dx)
    ratio = strength_ratio(stress, phi_deg, c)
    above = x[:, 1] > x[:, 1].min() + 2.5 * dx
    kb = int(np.argmax(np.where(bottom, ratio, -np.inf)))
    ka = int(np.argmax(np.where(above, ratio, -np.inf)))
    return {"thrust_effective_N_m": effective, "thrust_water_N_m": water,
            "thrust_N_m": effective + water,
            "base_shear_N_m": float(stress[right, 3].sum() * dx),
            "base_length_m": float(right.sum() * dx),
            "bottom_ratio_max": float(ratio[kb]), "bottom_ratio_at": x[kb].tolist(),
            "bottom_ratio_above_1_m": float((bottom & (ratio > 1.0)).sum() * dx),
            "interior_ratio_max": float(ratio[ka]), "interior_ratio_at": x[ka].tolist()}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m psph.verify.slope_statics",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path)
    ap.add_argument("--crest", type=float, default=141.5,
                    help="x of the particle column through the crest [m]")
    ap.add_argument("--dx", type=float, default=1.0)
    ap.add_argument("--phi", type=float, default=10.0, help="peak friction angle [deg]")
    ap.add_argument("--c", type=float, default=55e3, help="peak cohesion [Pa]")
    a = ap.parse_args(argv)
    with h5py.File(a.run / "particles.h5", "r") as f:
        g = f["snapshots/00000000"]
        s = base_statics(g["x"][:], g["stress"][:], g["p"][:], a.dx, a.crest, a.phi, a.c)
    for k, v in s.items():
        print(f"{k:26s} {v}")


if __name__ == "__main__":
    main()

"""Which Mohr-Coulomb state the flowing particles of a 3D collapse are in (issue 37,
docs/vv/collapse_3d.md): the Lode angle of the effective stress of every particle whose
plastic strain grew by more than `--threshold` since the snapshot before, for each
snapshot up to `--until`. theta = +30 deg is triaxial compression (one principal stress
more compressive than two equal others), 0 the state whose middle principal stress is the
mean (where the Drucker-Prager plane-strain fit of Eq. (16), xi = 0.160 at 30 deg, nearly
meets Mohr-Coulomb, sin(phi) / 3 = 0.167), -30 triaxial extension.

    .venv/bin/python bench/diagnostics/collapse_3d_lode.py runs/collapse_3d
    .venv/bin/python bench/diagnostics/collapse_3d_lode.py runs/collapse_3d_a3

Each row also counts the flowing particles at the apex by their depth: in the surface
row of their dx x dx column, one, two, and three or more rows below it.
"""

import argparse
from pathlib import Path

import h5py
import numpy as np

from psph.geometry.columns import column_index, column_tops


def lode_angles(stress: np.ndarray) -> np.ndarray:
    """Lode angle (deg) of stresses (n, 6) (xx, yy, zz, xy, yz, zx; tension positive):
    sin(3 theta) = -(3 sqrt(3) / 2) J3 / J2^(3/2); NaN where sqrt(J2) is below 1 Pa (an
    isotropic stress, the Drucker-Prager apex: no Lode angle)."""
    m = stress[:, :3].sum(axis=1) / 3.0
    xx, yy, zz = (stress[:, q] - m for q in range(3))
    xy, yz, zx = stress[:, 3], stress[:, 4], stress[:, 5]
    j2 = 0.5 * (xx ** 2 + yy ** 2 + zz ** 2) + xy ** 2 + yz ** 2 + zx ** 2
    j3 = xx * (yy * zz - yz ** 2) - xy * (xy * zz - yz * zx) + zx * (xy * yz - yy * zx)
    with np.errstate(invalid="ignore", divide="ignore"):
        arg = -(3.0 * np.sqrt(3.0) / 2.0) * j3 / j2 ** 1.5
    theta = np.degrees(np.arcsin(np.clip(arg, -1.0, 1.0)) / 3.0)
    return np.where(j2 > 1.0, theta, np.nan)


def apex_rows(x: np.ndarray, dx: float) -> np.ndarray:
    """Rows below the surface of its dx x dx plan column (0: the top particle) of each
    particle of x (n, 3)."""
    lo = x[:, :2].min(axis=0) - 0.5 * dx
    shape = tuple(np.floor((x[:, :2] - lo) / dx).astype(np.int64).max(axis=0) + 1)
    top = column_tops(x, lo, dx, shape)
    return np.round((top[column_index(x, lo, dx, shape)] - x[:, 2]) / dx).astype(np.int64)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path)
    ap.add_argument("--threshold", type=float, default=0.02)
    ap.add_argument("--until", type=float, default=1.0)
    ap.add_argument("--dx", type=float, default=0.05)
    a = ap.parse_args()
    print("| t (s) | flowing | median theta | share in [-30,-20) [-20,-10) [-10,10) "
          "[10,20) [20,30] | apex by rows below the surface 0 / 1 / 2 / 3+ |")
    print("|---|---|---|---|---|")
    with h5py.File(a.run / "particles.h5", "r") as f:
        prev = None
        for name in sorted(f["snapshots"]):
            g = f["snapshots"][name]
            t = float(g.attrs["time"])
            order = np.argsort(g["id"][:])
            eps = g["eps_p"][:][order]
            if prev is not None and t <= a.until + 1e-9:
                flowing = eps - prev > a.threshold
                theta = lode_angles(g["stress"][:][order][flowing])
                apex = int(np.isnan(theta).sum())
                rows = apex_rows(g["x"][:][order], a.dx)[flowing][np.isnan(theta)]
                by_rows = [int((rows == k).sum()) for k in range(3)] + [int((rows >= 3).sum())]
                theta = theta[~np.isnan(theta)]
                if len(theta):
                    share = np.histogram(theta, bins=[-30, -20, -10, 10, 20, 30])[0]
                    share = share / len(theta)
                    print(f"| {t:.2f} | {len(theta)} (+{apex} at the apex) | "
                          f"{np.median(theta):+.1f} | "
                          + " ".join(f"{v:.2f}" for v in share) + " | "
                          + " / ".join(str(v) for v in by_rows) + " |")
            prev = eps


if __name__ == "__main__":
    main()

"""How many of Cryer's sphere's particles the free-surface test drains, and how deep:
the 3D test of `psph/kernels/free_surface.py` ((trace(M) + its smallest eigenvalue) / 2
below 1.5) against the trace test it replaced on 2026-12-06 (trace(M) < 2.25), on the octant
of the scene `cryer` (a 1 m sphere, lattice points (i + 1/2) dx within it; its three
symmetry planes' mirror ghosts are the other octants' particles). docs/vv/cryer.md.

    python bench/diagnostics/free_surface_count.py 0.1 0.05
"""

import argparse

import numpy as np

from psph.kernels.free_surface import on_free_surface
from psph.kernels.spline import dw_cubic_dim

H_FACTOR = 1.2
OLD_TRACE = 2.25  # the 3D trace test until 2026-12-06


def moments(dx: float) -> tuple[np.ndarray, np.ndarray]:
    """The octant's particle positions and M of Eq. (22) at each (3 x 3, row-major)."""
    g = (np.arange(-int(1 / dx) - 1, int(1 / dx) + 1) + 0.5) * dx
    x = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T
    x = x[np.linalg.norm(x, axis=1) <= 1.0]
    octant = x[np.all(x > 0, axis=1)]
    h = H_FACTOR * dx
    m = np.zeros((len(octant), 9))
    for k, xi in enumerate(octant):
        d = x - xi
        r = np.linalg.norm(d, axis=1)
        near = (r > 0) & (r < 2 * h)
        d, r = d[near], r[near]
        dw = np.array([dw_cubic_dim(rr, h, 3) for rr in r])
        grad = -dw[:, None] * d / r[:, None]  # grad_i W_ij, x_i - x_j = -d
        m[k] = (dx ** 3 * d.T @ grad).ravel()  # sum_j V_j x_ji (x) grad_i W_ij
    return octant, m


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dx", type=float, nargs="+")
    args = ap.parse_args()
    print(f"{'dx':>6s} {'particles':>9s} {'trace test':>10s} {'new test':>12s} "
          f"{'deepest (dx below the surface)':>31s}")
    for dx in args.dx:
        x, m = moments(dx)
        old = m[:, 0] + m[:, 4] + m[:, 8] < OLD_TRACE
        new = np.array([on_free_surface(row, 0, 3) for row in m])
        depth = (1.0 - np.linalg.norm(x, axis=1)) / dx
        print(f"{dx:6g} {len(x):9d} {old.sum():10d} {new.sum():12d} "
              f"{depth[old].max():14.2f} -> {depth[new].max():.2f}")


if __name__ == "__main__":
    main()

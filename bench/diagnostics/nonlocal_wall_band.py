"""The non-local softening variable of a shear band lying on a wall (issue 17): eps_hat
of the band's rows and of the row above it, for a band of 1, 2 or 3 particle rows with
eps_p = 10 on the wall y = 0 of a 40 x 20 lattice, at l_c = 1.5, 2.12 and 3 dx, with the
plain (m = 1) and the over-non-local (m = 2) average, from the solver's kernel
(`nonlocal_strain`, with the wall's images).

    python bench/diagnostics/nonlocal_wall_band.py

The slope's basal band is such a band: l_c = 1.2 m is 2.12 dx at dx = 0.566 m and 3 dx
at 0.4 m (README, "Convergence of the landslide answers").
"""

import sys

import numpy as np

from psph.verify.nonlocal_average import nonlocal_strains

DX = 1.0
RATIOS = (1.5, 2.12, 3.0)


def band_on_wall(rows: int, ratio: float, m: float) -> np.ndarray:
    """eps_hat of the rows 1..rows + 1 above the wall (the middle column), the band's
    rows holding eps_p = 10, the rest 0."""
    g = (np.arange(40) + 0.5) * DX
    x = np.array(np.meshgrid(g, g[:20], indexing="xy")).reshape(2, -1).T.copy()
    n = len(x)
    eps = np.where(x[:, 1] < rows * DX, 10.0, 0.0)
    out = nonlocal_strains(x, np.full(n, DX * DX), eps, [ratio * DX], [[m]], walls=[(1, 0.0)],
                           h=0.6 * DX)[0]
    column = np.flatnonzero(np.abs(x[:, 0] - 20.5 * DX) < 1e-9)
    column = column[np.argsort(x[column, 1])]
    return out[column[:rows + 1]]


def main() -> int:
    print("eps_hat by row above the wall (band rows carry eps_p = 10; last: the row above)")
    heads = [f"l_c = {r:g} dx" for r in RATIOS]
    print(f"{'band rows':>9s} {'m':>3s} " + " ".join(f"{h:>22s}" for h in heads))
    for rows in (1, 2, 3):
        for m in (1.0, 2.0):
            cells = [" ".join(f"{v:5.2f}" for v in band_on_wall(rows, r, m)) for r in RATIOS]
            print(f"{rows:9d} {m:3g} " + " ".join(f"{c:>22s}" for c in cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())

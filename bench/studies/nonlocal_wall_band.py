"""The non-local softening variable of a shear band lying on a wall: eps_hat
of the band's rows and of the row above it, for a band of 1, 2 or 3 particle rows with
eps_p = 10 on the wall y = 0 of a 40 x 20 lattice, at l_c = 1.5, 2.12 and 3 dx, with the
plain (m = 1) and the over-non-local (m = 2) average, from the solver's kernel
(`nonlocal_strain`, with the wall's images).

    python bench/studies/nonlocal_wall_band.py            # the table (seconds)
    python bench/studies/nonlocal_wall_band.py --quick    # a one-row band only

The slope's basal band is such a band: l_c = 1.2 m is 2.12 dx at dx = 0.566 m and 3 dx
at 0.4 m (docs/vv/convergence.md). Prints the table, writes <out>/nonlocal_wall_band.json.
"""

import argparse
import json
import sys
from pathlib import Path

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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a band of one row only")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "out",
                    help="directory of nonlocal_wall_band.json (default bench/out)")
    args = ap.parse_args(argv)
    print("eps_hat by row above the wall (band rows carry eps_p = 10; last: the row above)")
    heads = [f"l_c = {r:g} dx" for r in RATIOS]
    print(f"{'band rows':>9s} {'m':>3s} " + " ".join(f"{h:>22s}" for h in heads))
    table = []
    for rows in (1,) if args.quick else (1, 2, 3):
        for m in (1.0, 2.0):
            bands = [band_on_wall(rows, r, m) for r in RATIOS]
            table += [{"band_rows": rows, "m": m, "l_c_over_dx": r, "eps_hat": b.tolist()}
                      for r, b in zip(RATIOS, bands, strict=True)]
            cells = [" ".join(f"{v:5.2f}" for v in b) for b in bands]
            print(f"{rows:9d} {m:3g} " + " ".join(f"{c:>22s}" for c in cells))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "nonlocal_wall_band.json").write_text(json.dumps(table, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Candidates of the 3D pair sweep's half stencil on cells of side 2h and of side h
(issue 37, docs/performance.md): on a lattice block (30 x 30 x 60 particles, the
throughput bench's 3D block without its walls), the candidates each particle's half
stencil visits, the pairs closer than 2h among them, and the share accepted, at
h = 1.2 dx (every shipped 3D scene) and 1.3 dx.

    .venv/bin/python bench/diagnostics/pair_grid_candidates.py
"""

import numba as nb
import numpy as np

from psph.kernels.neighbours import (
    cell_lists,
    forward_slots,
    half_stencil_rows,
    neighbour_pairs,
    next_cell,
)


@nb.njit(cache=True)
def count_candidates(cell_start, ncell, span):
    """Slots the half stencil visits over every particle (the sweep's candidate loop)."""
    ncx, ncy, ncz = ncell[0], ncell[1], ncell[2]
    total = 0
    cx, cy, cz = -1, 0, 0
    for c in range(ncx * ncy * ncz):
        cx, cy, cz = next_cell(cx, cy, cz, ncx, ncy)
        for sa in range(cell_start[c], cell_start[c + 1]):
            for row in range(half_stencil_rows(3, span)):
                s0, s1 = forward_slots(row, c, sa, cx, cy, cz, ncx, ncy, ncz, cell_start, 3,
                                       span)
                total += s1 - s0
    return total


def main() -> None:
    dx = 0.01
    g = (np.arange(30) + 0.5) * dx
    gz = (np.arange(60) + 0.5) * dx
    x = np.array(np.meshgrid(g, g, gz, indexing="ij")).reshape(3, -1).T.copy()
    n = len(x)
    print(f"{n} particles on a lattice, dx = {dx} m")
    print(f"{'h / dx':>6s} {'cells':>9s} {'runs':>5s} {'candidates/particle':>20s} "
          f"{'pairs/particle':>15s} {'accepted':>9s}")
    for hf in (1.2, 1.3):
        h = hf * dx
        for span, name in ((1, "side 2h"), (2, "side h")):
            cell_start, order, ncell = cell_lists(x, h, span=span)
            cand = count_candidates(cell_start, ncell, span)
            pairs = np.zeros((60 * n, 2), np.int64)
            m = neighbour_pairs(n, x, h, cell_start, order, ncell, pairs, span)
            print(f"{hf:6.1f} {name:>9s} {half_stencil_rows(3, span):5d} {cand / n:20.1f} "
                  f"{m / n:15.1f} {m / cand:9.1%}")


if __name__ == "__main__":
    main()

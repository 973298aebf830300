"""A cell list of the particle store's rows with its own arrays. `Simulation` keeps two:
the grid of side 2h (the pair sweep's in 2D; Shepard's, the boundary particles' and the
non-local strain's, binned in 3D only in scenes that have one of them) and, in 3D, the
pair sweep's grid of cells of side h (`neighbours.pair_cell_span`)."""

import numpy as np

from psph.kernels.neighbours import bin_particles, grid_bounds


class CellGrid:
    """Cells of side `size` on the global grid anchored at `origin` (the same cell
    coordinates on every rank), at most `cell_max` per axis; rows sorted by cell, then by
    key (`neighbours.bin_particles`)."""

    def __init__(self, origin: np.ndarray, size: float, cell_max: np.ndarray, cap: int):
        dim = len(origin)
        self.origin = origin
        self.size = size
        self.cell_max = cell_max
        self.lo = np.zeros(dim, np.int64)
        self.ncell = np.zeros(dim, np.int64)
        self.cell_start = np.zeros(1024, np.int64)
        self.fill = np.zeros(1024, np.int64)
        self.cell_of = np.zeros(cap, np.int64)
        self.order = np.zeros(cap, np.int64)

    def bin(self, x: np.ndarray, key: np.ndarray, n: int) -> None:
        """Sort rows 0..n-1 of x into cells (arrays grown to the store's rows as needed)."""
        if self.order.shape[0] < x.shape[0]:
            self.cell_of = np.zeros(x.shape[0], np.int64)
            self.order = np.zeros(x.shape[0], np.int64)
        grid_bounds(x, n, self.origin, self.size, self.cell_max, self.lo, self.ncell)
        nc = int(np.prod(self.ncell))
        if self.cell_start.shape[0] < nc + 1:
            self.cell_start = np.zeros(2 * nc + 1, np.int64)
            self.fill = np.zeros(2 * nc + 1, np.int64)
        bin_particles(x, key, n, self.origin, self.size, self.lo, self.ncell, self.cell_of,
                      self.cell_start, self.fill, self.order)

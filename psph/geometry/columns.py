"""Plan columns of 3D points: the size x size columns of a plan grid from `lo`, the column
holding each point, and the top of each column (the ground surface that a plan view, a
scarp's measure or a cut that follows the ground reads)."""

import numpy as np


def column_grid(lo, hi, size: float) -> tuple[int, int]:
    """(nx, ny): the columns covering the plan from lo to hi (at least one each way)."""
    span = np.asarray(hi, float) - np.asarray(lo, float)
    return tuple(int(n) for n in np.maximum(np.ceil(span / size), 1).astype(np.int64))


def column_index(x: np.ndarray, lo, size: float, shape) -> tuple[np.ndarray, np.ndarray]:
    """(ix, iy) of the column holding each point x (n, >= 2), clipped to the grid (a point
    on its edge takes the edge column)."""
    idx = np.floor((x[:, :2] - np.asarray(lo, float)) / size).astype(np.int64)
    return (np.clip(idx[:, 0], 0, shape[0] - 1), np.clip(idx[:, 1], 0, shape[1] - 1))


def column_tops(x: np.ndarray, lo, size: float, shape, lift: float = 0.0) -> np.ndarray:
    """(nx, ny): the highest z of the points x (n, 3) in each column, plus `lift` (dx / 2
    takes a particle's top to the surface); -inf where a column is empty."""
    top = np.full(tuple(shape), -np.inf)
    np.maximum.at(top, column_index(x, lo, size, shape), x[:, 2] + lift)
    return top

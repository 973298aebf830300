"""Particle generation from scene geometry (global, identical on every rank)."""

import numpy as np


def lattice_block(lo, hi, dx: float) -> np.ndarray:
    """Particles at the centres of a square lattice of spacing dx filling [lo, hi] (2D)."""
    nx = max(int(round((hi[0] - lo[0]) / dx)), 1)
    ny = max(int(round((hi[1] - lo[1]) / dx)), 1)
    xs = lo[0] + (np.arange(nx) + 0.5) * dx
    ys = lo[1] + (np.arange(ny) + 0.5) * dx
    gx, gy = np.meshgrid(xs, ys, indexing="xy")
    return np.column_stack([gx.ravel(), gy.ravel()])


def surface_layer(x: np.ndarray, side: str, dx: float) -> np.ndarray:
    """Mask of the outermost particle layer on `side` (left, right, bottom, top)."""
    axis = 0 if side in ("left", "right") else 1
    c = x[:, axis]
    if side in ("right", "top"):
        return c > c.max() - 0.5 * dx
    return c < c.min() + 0.5 * dx

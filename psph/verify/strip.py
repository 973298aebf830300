"""Reference values for the flexible strip footing of Section 4.3.

Undrained loading of a saturated elastic layer with incompressible constituents is
isochoric: plane-strain undrained Poisson's ratio 1/2, so the excess pore pressure equals
the mean total stress change. For a strip load q of half-width b on an elastic half-space
(Flamant / Poulos & Davis), sigma_x + sigma_z = 2 q alpha / pi and sigma_y = (sigma_x +
sigma_z) / 2, hence

    p = q alpha / pi,   alpha = atan((x + b) / z) - atan((x - b) / z),

the angle the loaded strip subtends at the point (x from the centre line, z the depth).
The fluid's finite K_l lowers this by the Skempton factor B ~ 1 - (n/K_l) K_sk (< 1 % here),
and the finite layer (8a deep) differs from the half-space by a few per cent near the
bottom; both are neglected.
"""

import math

import numpy as np

from psph.geometry.lattice import census, seed


def undrained_pressure(q: float, half_width: float, x, depth) -> np.ndarray:
    """Excess pore pressure (Pa) right after an undrained strip load q over |x| < b."""
    x = np.asarray(x, float)
    z = np.maximum(np.asarray(depth, float), 1e-12)
    alpha = np.arctan((x + half_width) / z) - np.arctan((x - half_width) / z)
    return q * alpha / math.pi


def loaded_half_width(scene) -> float:
    """Half-width of the load as discretised: loaded particles on the symmetry side x dx.
    The loaded particles are those of `surface_layer` (psph/physics/initial.py) within
    each load's range, seeded here from the outer lattice row only, not all particles."""
    dx = scene.particles.dx
    loaded = set()
    for load in scene.loads:
        axis = 0 if load.side in ("left", "right") else 1
        values, counts = census(scene, axis)
        present = values[counts > 0]
        if load.side in ("right", "top"):  # c > max - dx/2
            lo, hi = np.nextafter(present.max() - 0.5 * dx, np.inf), np.inf
        else:  # c < min + dx/2
            lo, hi = -np.inf, present.min() + 0.5 * dx
        x, key = seed(scene, axis, lo, hi)
        if load.range is not None:
            along = x[:, 1 - axis]
            key = key[(along >= load.range[0]) & (along <= load.range[1])]
        loaded.update(key.tolist())
    return float(len(loaded)) * dx

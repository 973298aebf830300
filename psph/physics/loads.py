"""Surface load time histories (Section 4.1: ramp then hold; Section 4.2: harmonic)."""

import math

import numpy as np


def load_magnitude(load, t: float) -> float:
    """Pressure (Pa) of one scene load at time t."""
    if load.history == "harmonic":
        return load.pressure * (1.0 - math.cos(load.omega * t))
    if load.ramp > 0.0 and t < load.ramp:
        return load.pressure * t / load.ramp
    return load.pressure


def load_values(loads, t: float, out: np.ndarray) -> np.ndarray:
    for i, load in enumerate(loads):
        out[i] = load_magnitude(load, t)
    return out

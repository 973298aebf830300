"""Surface load time histories of Lian et al. (2023): Section 4.1, a ramp then hold;
Section 4.2, the harmonic load q (1 - cos(omega t))."""

import math

import numpy as np


def load_magnitude(load, t: float) -> float:
    """The pressure of one scene load at time t.

    Parameters
    ----------
    load : Load
        the scene's load (pressure in Pa, ramp in s, omega in rad/s).
    t : float
        time (s).

    Returns
    -------
    float
        the pressure (Pa).
    """
    if load.history == "harmonic":
        return load.pressure * (1.0 - math.cos(load.omega * t))
    if load.ramp > 0.0 and t < load.ramp:
        return load.pressure * t / load.ramp
    return load.pressure


def load_values(loads, t: float, out: np.ndarray) -> np.ndarray:
    """The pressures of all scene loads at time t.

    Parameters
    ----------
    loads : list of Load
        the scene's loads.
    t : float
        time (s).
    out : (len(loads),) float64 array
        receives the pressures (Pa).

    Returns
    -------
    float64 array
        out.
    """
    for i, load in enumerate(loads):
        out[i] = load_magnitude(load, t)
    return out

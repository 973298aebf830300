"""Cubic spline kernel, Eq. (21), in 2D.

The paper prints the inner branch as 2/3 - q^2 + q^3/3, which is discontinuous at q = 1;
the standard cubic spline (Monaghan), continuous with its derivative, has q^3/2 and is what
is used here. Support radius 2h, normalisation alpha_d = 15 / (7 pi h^2) in 2D.
"""

import math

import numba as nb

ALPHA_2D = 15.0 / (7.0 * math.pi)


@nb.njit(cache=True, inline="always")
def w_cubic(r: float, h: float) -> float:
    """Kernel value W(r, h) of Eq. (21) in 2D (1/m^2)."""
    q = r / h
    a = ALPHA_2D / (h * h)
    if q < 1.0:
        return a * (2.0 / 3.0 - q * q + 0.5 * q * q * q)
    if q < 2.0:
        t = 2.0 - q
        return a * t * t * t / 6.0
    return 0.0


@nb.njit(cache=True, inline="always")
def dw_cubic(r: float, h: float) -> float:
    """Radial derivative dW/dr of Eq. (21) in 2D (1/m^3); <= 0 everywhere."""
    q = r / h
    a = ALPHA_2D / (h * h * h)
    if q < 1.0:
        return a * (-2.0 * q + 1.5 * q * q)
    if q < 2.0:
        t = 2.0 - q
        return -0.5 * a * t * t
    return 0.0

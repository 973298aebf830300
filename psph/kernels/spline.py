"""Cubic spline kernel, Eq. (21) of Lian et al. (2023), in 2D and 3D.

The paper prints the inner branch as 2/3 - q^2 + q^3/3, which is discontinuous at q = 1;
the standard cubic spline (Monaghan), continuous with its derivative, has q^3/2 and is what
is used here. Support radius 2h, normalisation alpha_d = 15 / (7 pi h^2) in 2D and
3 / (2 pi h^3) in 3D (Monaghan 1992; the kernel integrates to one in both).

`w_cubic_dim` and `dw_cubic_dim` take the dimension; `w_cubic` and `dw_cubic` are their
2D cases.
"""

import math

import numba as nb

ALPHA_2D = 15.0 / (7.0 * math.pi)
ALPHA_3D = 3.0 / (2.0 * math.pi)


@nb.njit(cache=True, inline="always")
def w_cubic_dim(r: float, h: float, dim: int) -> float:
    """Kernel value W(r, h) of Eq. (21).

    Parameters
    ----------
    r : float
        distance (m).
    h : float
        smoothing length (m).
    dim : int
        2 or 3.

    Returns
    -------
    float
        W (1/m^dim).
    """
    q = r / h
    a = ALPHA_2D / (h * h) if dim == 2 else ALPHA_3D / (h * h * h)
    if q < 1.0:
        return a * (2.0 / 3.0 - q * q + 0.5 * q * q * q)
    if q < 2.0:
        t = 2.0 - q
        return a * t * t * t / 6.0
    return 0.0


@nb.njit(cache=True, inline="always")
def dw_cubic_dim(r: float, h: float, dim: int) -> float:
    """Radial derivative dW/dr of Eq. (21).

    Parameters
    ----------
    r : float
        distance (m).
    h : float
        smoothing length (m).
    dim : int
        2 or 3.

    Returns
    -------
    float
        dW/dr (1/m^(dim+1)), <= 0 everywhere.
    """
    q = r / h
    a = ALPHA_2D / (h * h * h) if dim == 2 else ALPHA_3D / (h * h * h * h)
    if q < 1.0:
        return a * (-2.0 * q + 1.5 * q * q)
    if q < 2.0:
        t = 2.0 - q
        return -0.5 * a * t * t
    return 0.0


@nb.njit(cache=True, inline="always")
def w_cubic(r: float, h: float) -> float:
    """Kernel value W(r, h) of Eq. (21) in 2D.

    Parameters
    ----------
    r : float
        distance (m).
    h : float
        smoothing length (m).

    Returns
    -------
    float
        W (1/m^2).
    """
    return w_cubic_dim(r, h, 2)


@nb.njit(cache=True, inline="always")
def dw_cubic(r: float, h: float) -> float:
    """Radial derivative dW/dr of Eq. (21) in 2D.

    Parameters
    ----------
    r : float
        distance (m).
    h : float
        smoothing length (m).

    Returns
    -------
    float
        dW/dr (1/m^3), <= 0 everywhere.
    """
    return dw_cubic_dim(r, h, 2)

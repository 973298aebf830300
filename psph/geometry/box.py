"""The sides of the domain box in 2D and 3D: which axis each side is a plane of, at which
end, and on which side of it the soil lies. The vertical axis is the last one: y in 2D
(left, right, bottom, top), z in 3D (left, right, front, back, bottom, top)."""

import numpy as np

# side -> (axis, which end of the domain (0 min, 1 max), sign: +1 soil at larger x[axis])
SIDE_PLANES = {"left": (0, 0, 1.0), "right": (0, 1, -1.0),
               "bottom": (1, 0, 1.0), "top": (1, 1, -1.0)}
SIDE_PLANES_3D = {"left": (0, 0, 1.0), "right": (0, 1, -1.0),
                  "front": (1, 0, 1.0), "back": (1, 1, -1.0),
                  "bottom": (2, 0, 1.0), "top": (2, 1, -1.0)}


def side_planes(dim: int) -> dict[str, tuple[int, int, float]]:
    """The box sides of a `dim`-dimensional domain: (axis, end, sign) by name."""
    return SIDE_PLANES if dim == 2 else SIDE_PLANES_3D


def outward_normal(side: str, dim: int) -> np.ndarray:
    """The outward unit normal of a box side."""
    axis, _, sign = side_planes(dim)[side]
    normal = np.zeros(dim)
    normal[axis] = -sign
    return normal

"""Where the drained sides of a scene hold p = 0.

`pressure.drained_boundary = "mirror"` (default): p = 0 on the side's true surface. A wall
side (fixed or slip, with mirror ghosts) gets it from its ghosts, whose pore pressure is
mirrored antisymmetrically once the side drains (`kernels/ghosts.py`); a free side from
antisymmetric images across a plane (`kernels/images.py`) that starts on the soil's outer
surface (outer particle layer + dx/2) and follows that layer's mean displacement.

`"layer"`: p = 0 imposed on the outer particle layer (`drained_from` of the particles), dx/2
inside the surface, a drainage path dx/2 short. It suits a drained side that does not stay
a plane (the saturated collapses' top, which falls apart).
"""

import math

import numpy as np

from psph.geometry.box import side_planes
from psph.kernels.images import row_displacement
from psph.solver.exact_dots import ExactDots


class Drainage:
    """The drained sides of a scene, as the kernels need them at time t."""

    def __init__(self, scene, wall_sides: list[str], soil_extent):
        """`wall_sides`: the sides with mirror ghosts, in the solver's wall order;
        `soil_extent()`: (2, dim) the smallest and largest initial particle coordinates
        along each axis (for the free planes' first position), called (collectively) only
        when a free side drains."""
        self.mirror = (scene.pressure.drained_boundary == "mirror"
                       and scene.pressure.scheme != "none")
        self.dx = scene.particles.dx
        b = scene.boundaries

        def drains(side):
            return self.mirror and getattr(b, side).flow == "drained"

        self.wall_from = np.array([getattr(b, s).drained_from if drains(s) else math.inf
                                   for s in wall_sides])
        self.wall_drained = np.zeros(len(wall_sides), np.bool_)
        sides = side_planes(scene.dim)
        free = [s for s in sides if drains(s) and s not in wall_sides]
        self.plane_from = np.array([getattr(b, s).drained_from for s in free])
        self.planes = np.zeros((len(free), 4))  # axis, pos, sign, active (images.py)
        self.pos0 = np.zeros(len(free))
        bounds = soil_extent() if free else None
        for q, side in enumerate(free):
            axis, end, sign = sides[side]
            edge = bounds[end, axis]
            self.pos0[q] = edge - sign * 0.5 * self.dx
            self.planes[q] = (axis, self.pos0[q], sign, 0.0)
        self._row = np.zeros(0)
        self._ones = np.zeros(0)
        self._dots = ExactDots()

    @property
    def has_planes(self) -> bool:
        return len(self.planes) > 0

    def layer_clock(self, t: float) -> float:
        """The time the kernels compare with the particles' `drained_from` (p = 0 imposed
        on the outer layer): t in "layer" mode, never in "mirror" mode."""
        return -math.inf if self.mirror else t

    def update_walls(self, t: float) -> np.ndarray:
        """Which walls mirror p antisymmetrically at time t."""
        np.greater_equal(t, self.wall_from, out=self.wall_drained)
        return self.wall_drained

    def update_planes(self, t: float, store, slabs) -> np.ndarray:
        """Move each free plane to its first position plus the mean displacement of the
        outer particle layer (exact sums, the same bits on any rank count: the
        displacements and their count in one integer collective per plane, `exact_dots`),
        and mark the planes whose side has drained by t (planes[:, 3]: the Darcy images;
        the projection's correction images act from the start, `images.image_weights`)."""
        for q in range(len(self.planes)):
            axis, pos, sign = int(self.planes[q, 0]), self.planes[q, 1], self.planes[q, 2]
            if self._row.shape[0] < store.n_owned:
                self._row = np.zeros(store.cap)
                self._ones = np.ones(store.cap)
            m = row_displacement(store.n_owned, store.x, store.u, axis, pos, sign, self.dx,
                                 self._row)
            ones = self._ones
            total, count = self._dots(slabs, m, (self._row, ones), (ones, ones))
            if count > 0:
                self.planes[q, 1] = self.pos0[q] + total / count
            self.planes[q, 3] = 1.0 if t >= self.plane_from[q] else 0.0
        return self.planes

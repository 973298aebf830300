"""Rigid boundaries lined with boundary particles (the paper's virtual particles, ref.
[11]): polylines in 2D, surfaces in 3D; set-up, the rows each rank
holds, their state each step, contact.

The boundary particles of all polylines are built once on every rank: rows (k + 1/2) dx
from the line (`geometry/polylines.boundary_particles`), or with `rows = "lattice"` on the
domain's particle lattice (`lattice_particles`: the first boundary row dx from the soil's
lowest row in every column, as the mirror ghosts of a plane wall). Those of a surface
are the soil lattice's points within 2h behind it (`geometry/surfaces.py`). Their number
scales with the perimeter (the area in 3D), not the soil. They never
move or migrate: each step a rank appends those within its slab plus 4h after the wall
ghosts (rows n_real + n_wall_ghosts ..; the selection is recomputed only when the slab
moves), then, after the neighbour search, sets their state from the soil around them
(`kernels/boundary.py`, `kernels/boundary_3d.py`: Adami et al. 2012 with the plane
ghosts' conventions).

Partition independence: a boundary particle within 2h of an owned particle averages soil
up to 4h from the slab, so scenes with polylines use a halo (and a minimum slab width) of
4h instead of 2h (`halo_width`); with the key-ordered cell lists every rank then sums the
same particles in the same order, and 1 and N ranks give the same bits.
"""

from __future__ import annotations

import numpy as np

from psph.config.boundaries import points_of, triangles_of
from psph.config.schema import Scene
from psph.geometry.polylines import boundary_particles, lattice_particles
from psph.geometry.surfaces import surface_particles
from psph.kernels.boundary import (
    MOTION_FIXED,
    MOTION_FRICTION,
    MOTION_SLIP,
    boundary_contact,
    boundary_state,
    near_box,
    place_rows,
)
from psph.kernels.boundary_3d import boundary_state_3d
from psph.kernels.bundles import (
    BoundaryPoints,
    BoundaryRows,
    CellList,
    ContactFields,
    ContactGrid,
    WallFields,
    fields_of,
)
from psph.physics.softening import reach

_MOTION = {"fixed": MOTION_FIXED, "slip": MOTION_SLIP, "friction": MOTION_FRICTION}


def has_boundary_particles(scene: Scene) -> bool:
    """Whether the scene has polylines or surfaces lined with boundary particles."""
    return bool(scene.boundaries.polylines or scene.boundaries.surfaces)


def halo_width(scene: Scene) -> float:
    """Halo depth and minimum inner slab width: 2h, or 4h with boundary particles (their
    Shepard averages reach 2h beyond the 2h of the pair loop), or the support 2 l_c of a
    regularised softening if wider (psph/physics/softening.py)."""
    return max((4.0 if has_boundary_particles(scene) else 2.0) * scene.h, reach(scene))


class BoundaryParticles:
    """The boundary particles of `scene.boundaries.polylines` (2D) or `.surfaces` (3D)
    and their rows on this rank."""

    def __init__(self, scene: Scene, key_base: float):
        """key_base: the first sort key of the boundary particles (above every soil and
        ghost key), the same on every rank."""
        dx, h = scene.particles.dx, scene.h
        self.dim = scene.dim
        lo = np.array(scene.domain.min, float) - 2.0 * h
        hi = np.array(scene.domain.max, float) + 2.0 * h
        xs, ns, fs, motion, tan_phi, drained, weight = [], [], [], [], [], [], []
        walls = [(f"boundaries.polylines[{i}]", w)
                 for i, w in enumerate(scene.boundaries.polylines)]
        walls += [(f"boundaries.surfaces[{i}]", w)
                  for i, w in enumerate(scene.boundaries.surfaces)]
        for key, line in walls:
            if key.startswith("boundaries.surfaces"):
                pts, tri = triangles_of(line, key)
                x, n, f = surface_particles(pts, tri, line.soil, dx, h, scene.domain.min, lo,
                                            hi, key)
            elif line.rows == "lattice":  # the domain's lattice: dx from the soil's lowest
                pts = points_of(line, key)
                x, n, f = lattice_particles(pts, line.soil, dx, h, scene.domain.min, lo, hi)
            else:
                x, n, f = boundary_particles(points_of(line, key), line.soil, dx, h)
            inside = np.all((x >= lo) & (x <= hi), axis=1)  # beyond: no soil can reach
            xs.append(x[inside])
            ns.append(n[inside])
            fs.append(f[inside])
            m = int(inside.sum())
            motion.append(np.full(m, _MOTION[line.motion], np.int64))
            phi = line.friction_angle or 0.0
            tan_phi.append(np.full(m, np.tan(np.radians(phi))))
            drained.append(np.full(m, line.drained, np.bool_))
            weight.append(np.full(m, line.weight_friction, np.bool_))
        self.x = np.concatenate(xs)
        self.normal = np.concatenate(ns)
        self.foot = np.concatenate(fs)
        self.motion = np.concatenate(motion)
        self.tan_phi = np.concatenate(tan_phi)
        self.drained = np.concatenate(drained)
        # tan(phi_b) g_n of the weight friction, g_n the body force into the wall
        g_n = np.maximum(-(self.normal @ np.asarray(scene.gravity, float)), 0.0)
        self.weight_friction = np.where(np.concatenate(weight), self.tan_phi * g_n, 0.0)
        self.weight_dv = np.zeros_like(self.weight_friction)
        self.half_weight = 0.5 * g_n * dx  # per unit density: rho g_n dx / 2
        # in a saturated scene the effective stress carries the buoyant weight, and the
        # wall's Coulomb friction acts on it: rho - rho_l (the water's share is the pore
        # pressure's)
        self.rho_water = scene.material_list[0].rho_l if scene.pressure.scheme != "none" \
            else 0.0
        self.reach = dx
        self.key = key_base + np.arange(len(self.x), dtype=float)
        self.cell_volume = dx ** self.dim
        self.h = h
        self.width = halo_width(scene)
        self._slab_src = np.zeros(0, np.int64)
        self.src = np.zeros(0, np.int64)
        self._bbox = np.zeros((2, self.dim))
        self._slab = None
        self.first = 0
        self.n = 0

    def select(self, region: tuple[tuple[int, float, float], ...]) -> None:
        """The boundary particles within [lo - 4h, hi + 4h] along each (axis, lo, hi) of
        this rank's `region` (a slab's one axis, a box's two)."""
        if self._slab != region:
            inside = np.ones(len(self.x), bool)
            for axis, lo, hi in region:
                c = self.x[:, axis]
                inside &= (c >= lo - self.width) & (c <= hi + self.width)
            self._slab_src = np.flatnonzero(inside)
            self.src = np.zeros(len(self._slab_src), np.int64)
            self._slab = region

    def append(self, store) -> bool:
        """Append the selected boundary particles' rows after the ghosts (x, key, volume;
        the rest comes from `state`). False if the store had to grow first (its arrays
        moved: the caller rebuilds the ghosts and appends again). Only those within 2h of
        the box around the soil rows (owned and halo) are appended: the others interact with
        no soil this step, so leaving them out changes no sum."""
        nb = near_box(self.x, self._slab_src, store.x, store.n_real, 2.0 * self.h,
                      self._bbox, self.src)
        if store.ensure(store.n_total + nb + 64):
            return False
        self.first = store.n_total
        self.n = nb
        place_rows(self.first, nb, self.src, self.x, self.key, self.cell_volume, store.x,
                   store.key, store.vol)
        store.n_ghost += nb
        return True

    def state(self, store, v_slip, head_b, body, cell_of, cell_start, order, ncell) -> None:
        """Velocity, pressure, effective stress, porosity, density, conductivity and
        acceleration of the boundary rows (and v_slip = v on the real rows)."""
        st = store
        f = fields_of(WallFields, st.arrays, v_slip=v_slip)
        cells = CellList(cell_of, cell_start, order, ncell)
        if self.dim == 3:
            boundary_state_3d(st.n_real, self._rows(), self._points(), f, head_b, body, cells,
                              self.h)
            return
        boundary_state(st.n_real, self._rows(), self._points(), f, head_b, cells, self.h)

    def contact(self, store, origin, cell_size, grid_lo, ncell, cell_start, order,
                dt: float) -> int:
        """Put back owned particles found beyond a polyline or surface, and the weight
        friction of the particles touching a `weight_friction` wall (`boundary_contact`)."""
        st = store
        np.multiply(self.weight_friction, dt, out=self.weight_dv)
        return boundary_contact(st.n_owned, fields_of(ContactFields, st.arrays),
                                self._rows(), self._points(),
                                ContactGrid(origin, grid_lo, ncell, cell_start, order),
                                cell_size, self.h, self.reach, self.rho_water)

    def _rows(self) -> BoundaryRows:
        """This step's boundary rows of the store (`append`)."""
        return BoundaryRows(self.first, self.n, self.src)

    def _points(self) -> BoundaryPoints:
        """The boundary particles' per-particle arrays, as the kernels take them."""
        return BoundaryPoints(self.motion, self.tan_phi, self.drained, self.normal, self.foot,
                              self.weight_dv, self.half_weight)

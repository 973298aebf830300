"""Scene models of the boundaries: the sides of the domain box (mirror ghosts,
`kernels/ghosts.py`), rigid polylines (2D) and rigid surfaces (3D) lined with boundary
particles, the virtual particles of Lian et al. (2023) (`psph/solver/boundary.py`).

A polyline is given by its points [[x, z], ...] (inline or a CSV file, as the ground
profiles of `geometry/profiles.py`) and the side the soil is on: "above" or "below" for a
profile z(x) (x strictly increasing), "left" or "right" for a wall x(z) (z strictly
increasing). The boundary particles fill the other side.
"""

from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from psph.errors import SceneRule
from psph.geometry.box import side_planes
from psph.geometry.profiles import ProfileError, read_profile


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, validate_default=True)


class Boundary(_Model):
    """One side of the domain box: wall motion and pore-water flow condition."""

    motion: Literal["free", "slip", "fixed"] = Field(
        "free", description="\"free\" (no wall), \"slip\" (free-slip wall) or \"fixed\" "
        "(no slip)")
    flow: Literal["impermeable", "drained"] = Field(
        "impermeable", description="\"impermeable\" or \"drained\" (p = 0 on the side from "
        "drained_from)")
    drained_from: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Time a drained side starts to drain; impermeable before [s]")
    symmetry: bool = Field(
        False, description="true: the side is a symmetry plane of the problem (a half, "
        "quarter or octant model); needs motion = \"slip\" and soil within dx of the "
        "side (a check only: the wall is the same free-slip wall)")


class _RigidWall(_Model):
    """What a rigid wall lined with boundary particles does: its motion, friction and
    drainage (`kernels/boundary.py`, `kernels/boundary_3d.py`)."""

    motion: Literal["fixed", "slip", "friction"] = Field(
        "fixed", description="\"fixed\" (no slip), \"slip\" (frictionless) or "
        "\"friction\" (Coulomb)")
    friction_angle: float | None = Field(
        None, description="Wall friction angle φ_b, 0 ≤ φ_b < 90; required with and only "
        "with motion = \"friction\" [deg]")
    drained: bool = Field(False, description="true holds p = 0 on the wall; false is "
                          "impermeable")
    # docs/vv/collapse_3d.md: a layer one particle thick at the Drucker-Prager apex has no
    # stress for the wall's Coulomb traction to act on, and slides on as a film
    weight_friction: bool = Field(
        False, description="true: a soil particle within dx of the wall also loses, each "
        "step, up to tan(φ_b) g_n Δt of its velocity along the wall (the Coulomb friction of "
        "its own weight, g_n the body force into the wall), for the share of that weight "
        "its own normal stress does not carry (the buoyant weight in a saturated scene); "
        "needs motion = \"friction\"")


class Polyline(_RigidWall):
    """A rigid boundary along a polyline, fixed in space (`[[boundaries.polylines]]`).

    motion: "fixed" (no slip), "slip" (frictionless) or "friction" (Coulomb, with
    `friction_angle` phi_b in degrees, 0 <= phi_b < 90: the wall's shear traction is at
    most tan(phi_b) times the normal effective traction). drained: p = 0 on the line
    (the pore pressure of the boundary particles is antisymmetric); else impermeable.
    rows: "line" (rows (k + 1/2) dx from the line, `polylines.boundary_particles`) or
    "lattice" (on the soil's lattice, dx from its lowest row in every column,
    `polylines.lattice_particles`: for seeded soil at rest on a gently dipping line).
    weight_friction (with motion = "friction"): the soil particles within dx of the wall
    also get the Coulomb friction of their own weight (`kernels/boundary.boundary_contact`)."""

    points: list[list[float]] | str = Field(
        description="Points [[x, z], ...] or a CSV path: a profile increasing in x, or a "
        "wall increasing in z [m]")
    soil: Literal["above", "below", "left", "right"] = Field(
        description="Side the soil is on: \"above\"/\"below\" (profile) or "
        "\"left\"/\"right\" (wall)")
    rows: Literal["line", "lattice"] = Field(
        "line", description="Boundary rows \"line\" ((k + ½) dx from the line) or "
        "\"lattice\" (on the soil's lattice)")


class Surface(_RigidWall):
    """A rigid surface in 3D, fixed in space (`[[boundaries.surfaces]]`), lined with
    boundary particles on the soil's lattice (`geometry/surfaces.py`): a mesh file meshio
    reads (STL, OBJ, PLY, VTK, ...; its triangles and quads), an elevation grid (two
    triangles a cell, `geometry/grids.py`), or vertices and triangles inline. soil:
    "above" / "below" a surface z(x, y), or "outside" / "inside" a closed one. motion,
    friction_angle, weight_friction and drained as on a polyline."""

    mesh: str | None = Field(None, description="Path of a surface mesh file meshio reads "
                             "(triangles, quads); or give grid, or vertices and triangles")
    grid: str | None = Field(None, description="Path of an elevation grid (ESRI .asc or an "
                             "x, y, z CSV), two triangles a cell with data: a bedrock")
    vertices: list[list[float]] | None = Field(
        None, description="Inline vertices [[x, y, z], ...] [m]")
    triangles: list[list[int]] | None = Field(
        None, description="Inline triangles [[i, j, k], ...], indices into vertices")
    soil: Literal["above", "below", "outside", "inside"] = Field(
        description="Side the soil is on: \"above\"/\"below\" (a surface z(x, y)) or "
        "\"outside\"/\"inside\" (a closed surface)")


def triangles_of(surface: Surface, key: str = "surface") -> tuple[np.ndarray, np.ndarray]:
    """(points (k, 3), triangles (m, 3)) of a surface, from its mesh file or inline.
    Raises SceneRule / SceneError (one line naming `key`)."""
    from psph.errors import SceneError
    from psph.geometry.shapes import mesh_triangles

    given = [k for k in ("mesh", "grid") if getattr(surface, k) is not None]
    if surface.vertices is not None or surface.triangles is not None:
        given.append("vertices and triangles")
    if len(given) != 1:
        raise SceneRule(key, " and ".join(given) or "none",
                        "give either mesh (a file), grid (an elevation grid) or vertices "
                        "and triangles")
    if surface.grid is not None:
        from psph.geometry.grids import GridError, grid_triangles, read_grid

        try:
            points, tri = grid_triangles(read_grid(surface.grid))
        except GridError as e:
            raise SceneRule(f"{key}.grid = {e.where}", e.value, e.rule) from None
        if not len(tri):
            raise SceneRule(f"{key}.grid", surface.grid, "no cell with data at its four "
                            "corners")
        return points, tri
    if surface.mesh is not None:
        from pathlib import Path

        if not Path(surface.mesh).is_file():
            raise SceneRule(f"{key}.mesh", surface.mesh, "no such file")
        points, tri = mesh_triangles(surface.mesh, f"{key}.mesh = {surface.mesh!r}")
        if not len(tri) or points.shape[1] != 3:
            raise SceneError(f"{key}.mesh = {surface.mesh!r}: no triangle or quad faces "
                             "in 3D")
        if not np.all(np.isfinite(points)):
            raise SceneError(f"{key}.mesh = {surface.mesh!r}: non-finite vertex "
                             "coordinates")
        return points, tri
    if surface.vertices is None or surface.triangles is None:
        raise SceneRule(key, "vertices" if surface.triangles is None else "triangles",
                        "inline needs both vertices and triangles")
    try:
        points = np.asarray(surface.vertices, float)
    except ValueError:
        points = np.zeros((0, 0))
    if points.ndim != 2 or points.shape[1] != 3 or not len(points):
        raise SceneRule(f"{key}.vertices", "given", "needs [[x, y, z], ...], three "
                        "numbers a vertex")
    if not np.all(np.isfinite(points)):
        raise SceneRule(f"{key}.vertices", "non-finite", "coordinates must be finite")
    try:
        tri = np.asarray(surface.triangles, np.int64)
    except (ValueError, TypeError):
        tri = np.zeros((0, 0), np.int64)
    if tri.ndim != 2 or tri.shape[1] != 3 or not len(tri):
        raise SceneRule(f"{key}.triangles", "given", "needs [[i, j, k], ...], three "
                        "vertex indices a triangle")
    if tri.min() < 0 or tri.max() >= len(points):
        raise SceneRule(f"{key}.triangles", int(tri.max() if tri.max() >= len(points)
                                                else tri.min()),
                        f"vertex indices run from 0 to {len(points) - 1}")
    return points, tri


def points_of(line: Polyline, key: str = "polyline"):
    """(k, 2) points of a polyline: a profile in x ("above"/"below") or in z
    ("left"/"right"), strictly increasing in that coordinate. Raises SceneRule."""
    axis = 0 if line.soil in ("above", "below") else 1
    try:
        return read_profile(line.points, axis=axis)
    except ProfileError as e:
        where = f"{key}.points" + ("" if e.where in ("points", "file") else f" {e.where}")
        rule = e.rule + (f" (soil = '{line.soil}')" if "increase" in e.rule else "")
        raise SceneRule(where, e.value, rule) from None


class Boundaries(_Model):
    left: Boundary = Field(Boundary(), description="Left side of the domain box, x = "
                           "domain.min[0] (wall motion, flow)")
    right: Boundary = Field(Boundary(), description="Right side of the domain box, x = "
                            "domain.max[0] (wall motion, flow)")
    bottom: Boundary = Field(Boundary(), description="Bottom side of the domain box, y = "
                             "domain.min[1] (wall motion, flow)")
    top: Boundary = Field(Boundary(), description="Top side of the domain box, y = "
                          "domain.max[1] (wall motion, flow)")
    front: Boundary = Field(Boundary(), description="3D only: the side y = domain.min[1] "
                            "(bottom and top are then z = domain.min[2], domain.max[2])")
    back: Boundary = Field(Boundary(), description="3D only: the side y = domain.max[1]")
    polylines: list[Polyline] = Field([], description="2D only: rigid polylines lined with "
                                      "boundary particles")
    surfaces: list[Surface] = Field([], description="3D only: rigid surfaces lined with "
                                    "boundary particles")

    @model_validator(mode="after")
    def _symmetry(self) -> "Boundaries":
        """A symmetry plane is a free-slip wall (its mirror ghosts are the other half's
        particles). Whether the soil touches it is checked on the seeded particles
        (`psph.config.rules.check_symmetry_planes`)."""
        for side in ("left", "right", "front", "back", "bottom", "top"):
            b = getattr(self, side)
            if b.symmetry and b.motion != "slip":
                raise SceneRule(f"boundaries.{side}.symmetry", True,
                                "a symmetry plane is a free-slip wall (motion = \"slip\"), "
                                f"got motion = \"{b.motion}\"")
        return self

    @model_validator(mode="after")
    def _polylines(self) -> "Boundaries":
        walls = [(f"boundaries.polylines[{i}]", line) for i, line in enumerate(self.polylines)]
        walls += [(f"boundaries.surfaces[{i}]", sf) for i, sf in enumerate(self.surfaces)]
        for key, line in walls:
            if isinstance(line, Polyline):
                points_of(line, key)
            phi = line.friction_angle
            if line.motion == "friction":
                if phi is None:
                    raise SceneRule(f"{key}.friction_angle", None,
                                    "required with motion = 'friction' (degrees)")
                if not 0.0 <= phi < 90.0:
                    raise SceneRule(f"{key}.friction_angle", phi,
                                    "must be in [0, 90) degrees")
            elif phi is not None:
                raise SceneRule(f"{key}.friction_angle", phi,
                                f"only with motion = 'friction' (motion is '{line.motion}')")
            if line.weight_friction and line.motion != "friction":
                raise SceneRule(f"{key}.weight_friction", True,
                                f"only with motion = 'friction' (motion is '{line.motion}')")
        return self


class PlaneWalls(NamedTuple):
    """The sides of the domain box that are walls (motion not "free"), in the order left,
    right, (front, back,) bottom, top: the plane x[axis] = pos, the sign of the soil's
    side, fixed or free-slip."""

    sides: list[str]
    axis: np.ndarray
    pos: np.ndarray
    sign: np.ndarray
    fixed: np.ndarray


def plane_walls(boundaries: Boundaries, lo, hi) -> PlaneWalls:
    """The walls of `boundaries` on the domain box [lo, hi] (`domain.min`, `domain.max`;
    their length is the dimension)."""
    planes = side_planes(len(lo))
    walls = [(side, b) for side in planes
             if (b := getattr(boundaries, side)).motion != "free"]
    ends = (lo, hi)
    return PlaneWalls(
        [side for side, _ in walls],
        np.array([planes[s][0] for s, _ in walls], np.int64),
        np.array([ends[planes[s][1]][planes[s][0]] for s, _ in walls], float),
        np.array([planes[s][2] for s, _ in walls], float),
        np.array([b.motion == "fixed" for _, b in walls], np.bool_))

"""The rules between the keys of a scene, checked once its sections are valid: the
scene's model validator (`psph.config.schema.Scene`) calls `check_scene`. Each rule raises
`SceneRule` (key, value, rule), which `psph.config.load.validate` turns into one line and
exit 2."""

import math
from pathlib import Path

import numpy as np

from psph.config.boundaries import triangles_of
from psph.config.materials import check_materials
from psph.errors import SceneRule as _Rule
from psph.geometry.box import side_planes
from psph.geometry.grids import (
    GridError,
    check_cover,
    check_layer_grids,
    check_table_over_bedrock,
    is_grid_file,
    read_grid,
)
from psph.geometry.lattice import lattice_axes
from psph.geometry.profiles import ProfileError, check_layer_profiles, check_water_table
from psph.geometry.solids import read_surface
from psph.geometry.surfaces import soil_normals
from psph.physics.limits import (
    TPI_ALPHA_MAX,
    solid_dt_limit,
    tpi_dt,
    tpi_gain,
    tpi_gain_limit,
    undrained_dt_limit,
)
from psph.verify.terzaghi import column_drainage


def check_scene(scene):
    """The rules between keys of a scene whose sections are valid (`Scene`'s model
    validator): the domain, the particle sources, the materials, the initial state,
    probes, the schemes and the time step against Eq. (41) and TPI's bounds. Sets
    `scene.material` to the first material; raises `SceneRule` (key, value, rule)."""
    check_dimension(scene)
    lo, hi = scene.domain.min, scene.domain.max
    dim = scene.dim
    for d in range(dim):
        if hi[d] <= lo[d]:
            raise _Rule(f"domain.max[{d}]", hi[d], f"must exceed domain.min[{d}] = {lo[d]}")
    pa = scene.particles
    if not (pa.blocks or pa.polygons or pa.meshes or pa.layers or pa.spheres or pa.cylinders):
        raise _Rule("particles", "no blocks, polygons, meshes or layers",
                    "give at least one [[particles.blocks]], [[particles.polygons]], "
                    "[[particles.meshes]] or [[particles.layers]]")
    for il, layer in enumerate(pa.layers):
        if dim == 2:
            check_layer_profiles(layer, f"particles.layers[{il}]")
        else:  # elevation grids, with data over every lattice column
            axes = lattice_axes(lo, hi, scene.particles.dx)
            check_layer_grids(layer, f"particles.layers[{il}]", axes[0], axes[1])
    for ip, poly in enumerate(pa.polygons):
        for iv, v in enumerate(poly.vertices):
            for d in range(2):
                if not lo[d] - 1e-12 <= v[d] <= hi[d] + 1e-12:
                    raise _Rule(f"particles.polygons[{ip}].vertices[{iv}]", v,
                                f"outside the domain [{lo}, {hi}]")
    for ir, rm in enumerate(scene.remove):
        box = rm.min is not None and rm.max is not None
        if box == (rm.polygon is not None) or (rm.min is None) != (rm.max is None):
            raise _Rule(f"remove[{ir}]", "region", "give either min and max, or polygon")
        if rm.depth is not None and (rm.polygon is None or dim == 2):
            raise _Rule(f"remove[{ir}].depth", rm.depth, "only with a polygon in plan in a "
                        "3D scene (a 2D polygon is the region itself)")
    for im, mesh in enumerate(pa.meshes):
        if not Path(mesh.file).is_file():
            raise _Rule(f"particles.meshes[{im}].file", mesh.file, "no such file")
        if dim == 3:  # a closed surface, read once here so that bad input stops early
            read_surface(mesh.file, f"particles.meshes[{im}].file")
    for i, surface in enumerate(scene.boundaries.surfaces):  # read and oriented once here
        key = f"boundaries.surfaces[{i}]"
        points, tri = triangles_of(surface, key)
        soil_normals(points, tri, surface.soil, key)
    for ib, b in enumerate(scene.particles.blocks):
        for d in range(dim):
            if b.max[d] <= b.min[d]:
                raise _Rule(f"particles.blocks[{ib}].max[{d}]", b.max[d],
                            f"must exceed particles.blocks[{ib}].min[{d}] = {b.min[d]}")
            if b.min[d] < lo[d] - 1e-12:
                raise _Rule(f"particles.blocks[{ib}].min[{d}]", b.min[d],
                            f"particles outside the walls (domain.min[{d}] = {lo[d]})")
            if b.max[d] > hi[d] + 1e-12:
                raise _Rule(f"particles.blocks[{ib}].max[{d}]", b.max[d],
                            f"particles outside the walls (domain.max[{d}] = {hi[d]})")
    mats = check_materials(scene)
    if scene.material is None:
        scene.material = mats[0]
    if scene.trigger is not None and not any(m.model == "drucker_prager" for m in mats):
        raise _Rule("trigger", "[trigger]", "needs a drucker_prager material (it reduces "
                    "the strength and starts the softening of Eq. 17-19)")
    table = scene.initial.water_table
    if dim == 3 and isinstance(table, (int, float)):
        if table < lo[2]:
            raise _Rule("initial.water_table", table, f"below the domain's floor z = "
                        f"{lo[2]:g} m")
    elif dim == 3 and isinstance(table, str) and table != "surface":
        if not Path(table).is_file():
            raise _Rule("initial.water_table", table, "no such file")
        if not is_grid_file(table):
            raise _Rule("initial.water_table", table, "in 3D a water table is a level or an "
                        "elevation grid (an ESRI .asc file or an x, y, z CSV)")
        if scene.verification.reference == "collapse":
            raise _Rule("initial.water_table", table, "a level only with the plane-strain "
                        "collapse metrics (verification.reference = 'collapse')")
        dx = scene.particles.dx
        # the columns of the domain's lattice and of every block's own
        lattices = [lattice_axes(lo, hi, dx)] + [lattice_axes(b.min, b.max, dx)
                                                 for b in scene.particles.blocks]
        gx = np.concatenate([np.meshgrid(c[0], c[1])[0].ravel() for c in lattices])
        gy = np.concatenate([np.meshgrid(c[0], c[1])[1].ravel() for c in lattices])
        try:
            check_cover(read_grid(table), gx, gy, "the soil's lattice columns need a "
                        "water table")
        except GridError as e:
            raise _Rule(f"initial.water_table = {e.where}", e.value, e.rule) from None
    elif table is not None and table != "surface":
        try:
            check_water_table(table, scene.domain.min, scene.domain.max)
        except ProfileError as e:
            where = "" if e.where in ("points", "file", "level") else f" {e.where}"
            raise _Rule(f"initial.water_table{where}", e.value, e.rule) from None
    if dim == 3 and pa.layers and scene.pressure.scheme != "none" and table is not None \
            and table != "surface":
        check_saturated_layers(scene, table)
    if (scene.initial.k0 is not None or scene.initial.water_table is not None) \
            and scene.gravity[dim - 1] >= 0.0:
        key = "initial.k0" if scene.initial.k0 is not None else "initial.water_table"
        raise _Rule(key, getattr(scene.initial, key.split(".")[1]),
                    f"needs gravity along -{'yz'[dim - 2]} (gravity = {scene.gravity})")
    if scene.initial.undrained_load:
        check_undrained_load(scene)
    for name, pt in scene.output.probes.items():
        for d in range(dim):
            if not lo[d] <= pt[d] <= hi[d]:
                raise _Rule(f"output.probes.{name}", pt,
                            f"probe outside the domain [{lo}, {hi}]")
    for kind in ("polylines", "surfaces"):
        if scene.pressure.scheme == "projection" and getattr(scene.boundaries, kind):
            raise _Rule("pressure.scheme", "projection", f"not yet with boundaries.{kind}")
    if scene.pressure.recycle == 1:
        raise _Rule("pressure.recycle", 1, "0 (off) or at least 2 basis vectors")
    if scene.pressure.momentum != "pair" and scene.pressure.scheme not in ("explicit", "tpi"):
        raise _Rule("pressure.momentum", scene.pressure.momentum,
                    "needs pressure.scheme 'explicit' or 'tpi' (the projection's velocity "
                    "correction is pair-symmetric)")
    if scene.verification.reference == "terzaghi":
        check_terzaghi_reference(scene)
    if scene.time.end is None:
        if scene.verification.reference == "none" or not scene.verification.tv:
            raise _Rule("time.end", None, "required (no verification.tv to derive it from)")
    if scene.time.dt is not None and not scene.time.allow_dt_above_solid_limit:
        limit = solid_dt_limit(scene)
        if scene.time.dt > limit:
            raise _Rule("time.dt", scene.time.dt,
                        f"above the solid limit Eq. (41) {limit:.3e} s "
                        "(set time.allow_dt_above_solid_limit = true to force)")
        if scene.pressure.scheme == "explicit" and scene.time.dt > undrained_dt_limit(scene):
            raise _Rule("time.dt", scene.time.dt,
                        f"above the undrained wave limit {undrained_dt_limit(scene):.3e} s "
                        "of the explicit pressure update (Eq. 41 with the undrained "
                        "modulus; set time.allow_dt_above_solid_limit = true to force)")
    if scene.pressure.scheme == "tpi":
        for i, m in enumerate(scene.material_list):
            if m.k == 0.0:
                key = "material.k" if len(scene.material_list) == 1 else f"materials[{i}].k"
                raise _Rule(key, 0.0, "no flow runs with the explicit or projection scheme: "
                            "TPI's Eq. (38) has no storage term, so it needs k > 0")
    if scene.pressure.scheme == "tpi" and not scene.pressure.allow_unstable:
        check_tpi_stability(scene)
    check_integrator(scene)
    return scene


def check_saturated_layers(scene, table) -> None:
    """A coupled 3D scene of layers between elevation grids: its water table (a level or
    a grid) nowhere below the bedrock (the layers' lowest bottom) at the domain's
    lattice columns (`grids.check_table_over_bedrock`)."""
    xs, ys = lattice_axes(scene.domain.min, scene.domain.max, scene.particles.dx)[:2]
    gx, gy = (a.ravel() for a in np.meshgrid(xs, ys))
    bottoms = [read_grid(layer.bottom) for layer in scene.particles.layers]
    try:
        check_table_over_bedrock(read_grid(table) if isinstance(table, str) else table,
                                 bottoms, gx, gy)
    except GridError as e:
        raise _Rule(f"initial.water_table = {e.where}", e.value, e.rule) from None


def is_slope_3d(scene) -> bool:
    """A 3D scene of soil between elevation grids only (`verify/slope_3d.py`)."""
    p = scene.particles
    return scene.dim == 3 and bool(p.layers) and not (p.blocks or p.cylinders or p.spheres
                                                      or p.meshes)


def check_collapse_3d(scene) -> None:
    """A 3D collapse is either axisymmetric (exactly one [[particles.cylinders]],
    `verify/collapse_3d.py`), a slope (layers only: the centre line's section and the
    plan, `verify/slope_3d.py`) or a plane-strain slab (blocks only, between slip walls at
    the front and the back: the 2D metrics in the x-z plane, `verify/collapse.py`)."""
    p = scene.particles
    if len(p.cylinders) == 1 or is_slope_3d(scene):
        return
    b = scene.boundaries
    slab = (not p.cylinders and not p.spheres and not p.meshes and p.blocks
            and all(getattr(b, side).motion == "slip" for side in ("front", "back")))
    if not slab:
        raise _Rule("verification.reference", "collapse", "in 3D needs exactly one "
                    "[[particles.cylinders]] (the axisymmetric collapse), layers only (a "
                    "slope) or blocks between "
                    "slip walls at the front and the back (a plane-strain slab)")
    y0, y1 = scene.domain.min[1], scene.domain.max[1]
    for i, blk in enumerate(p.blocks):
        if abs(blk.min[1] - y0) > 1e-9 * max(1.0, abs(y1 - y0)) \
                or abs(blk.max[1] - y1) > 1e-9 * max(1.0, abs(y1 - y0)):
            raise _Rule(f"particles.blocks[{i}]", f"y from {blk.min[1]:g} to {blk.max[1]:g}",
                        f"a plane-strain slab fills the domain between its front and back "
                        f"walls, y from {y0:g} to {y1:g} (verification.reference = "
                        "'collapse' in 3D)")


def check_dimension(scene) -> None:
    """Every point and vector of the scene has `dim` components; in 3D the sources and
    boundaries that are 2D only so far are refused, in 2D the 3D-only sides."""
    dim = scene.dim
    vectors = [("domain.min", scene.domain.min), ("domain.max", scene.domain.max),
               ("gravity", scene.gravity)]
    for ib, b in enumerate(scene.particles.blocks):
        vectors += [(f"particles.blocks[{ib}].min", b.min), (f"particles.blocks[{ib}].max",
                                                             b.max)]
    vectors += [(f"output.probes.{k}", v) for k, v in scene.output.probes.items()]
    for ir, rm in enumerate(scene.remove):
        vectors += [(f"remove[{ir}].{k}", v) for k, v in (("min", rm.min), ("max", rm.max))
                    if v is not None]
    vectors += [(f"particles.spheres[{i}].centre", sp.centre)
                for i, sp in enumerate(scene.particles.spheres)]
    vectors += [(f"particles.cylinders[{i}].base", cy.base)
                for i, cy in enumerate(scene.particles.cylinders)]
    for il, ld in enumerate(scene.loads):
        if ld.side == "surface" and ld.range is not None:
            raise _Rule(f"loads[{il}].range", ld.range, "not with side = 'surface' (every "
                        "exposed face is loaded)")
    if scene.verification.reference == "cryer":
        check_cryer(scene)
    if scene.verification.reference == "collapse" and dim == 3:
        check_collapse_3d(scene)
    for key, v in vectors:
        if len(v) != dim:
            raise _Rule(key, v, f"needs {dim} components in a {dim}D scene (dim = {dim}; "
                        "a 3D scene gives [x, y, z], a 2D one [x, y])")
    b = scene.boundaries
    for kind in ("spheres", "cylinders"):
        if dim == 2 and getattr(scene.particles, kind):
            raise _Rule(f"particles.{kind}", f"{len(getattr(scene.particles, kind))} given",
                        "3D only (a 2D scene takes polygons)")
    if dim == 2 and b.surfaces:
        raise _Rule("boundaries.surfaces", f"{len(b.surfaces)} given", "3D only (a 2D scene "
                    "takes boundaries.polylines)")
    if dim == 2 and scene.decomposition.axis == "z":
        raise _Rule("decomposition.axis", "z", "3D only (a 2D scene cuts slabs along x or y)")
    if dim == 2:
        for side in ("front", "back"):
            if side in b.model_fields_set:
                raise _Rule(f"boundaries.{side}", getattr(b, side).motion,
                            "3D only (a 2D scene has left, right, bottom, top)")
        return
    pa = scene.particles
    two_d = [("particles.polygons", pa.polygons),
             ("boundaries.polylines", b.polylines),
             ("loads.range", [ld for ld in scene.loads if ld.range is not None]),
             ("initial.water_table", [] if scene.initial.water_table is None
              or isinstance(scene.initial.water_table, (float, str)) else [1]),
             ("initial.undrained_load", [1] if scene.initial.undrained_load else [])]
    for key, items in two_d:
        if items:
            raise _Rule(key, f"{len(items)} given", "2D only so far (dim = 3 takes "
                        "particles.blocks, particles.meshes (closed surfaces), particles.layers "
                        "between elevation grids, box sides, boundaries.surfaces, a level "
                        "water table)")


def check_cryer(scene) -> None:
    """`verification.reference = "cryer"`: one sphere, one load on its surface, a probe
    named "centre" (`psph/verify/cryer.py`)."""
    key = "verification.reference"
    if scene.dim != 3 or len(scene.particles.spheres) != 1:
        raise _Rule(key, "cryer", "needs a 3D scene with exactly one [[particles.spheres]]")
    if len(scene.loads) != 1 or scene.loads[0].side != "surface":
        raise _Rule(key, "cryer", "needs exactly one [[loads]] with side = 'surface'")
    if "centre" not in scene.output.probes:
        raise _Rule(key, "cryer", "needs output.probes.centre (the particle nearest the "
                    "sphere's centre)")


def check_integrator(scene) -> None:
    """The projection's default integrator is the symplectic one, the others' the one-sweep
    step; the one-sweep step with the projection is refused (forward Euler for
    the skeleton, which the projection's undamped undrained mode does not absorb)."""
    if scene.time.integrator is None:
        scene.time.integrator = "symplectic" if scene.pressure.scheme == "projection" \
            else "euler"
    if scene.pressure.scheme == "projection" and scene.time.integrator == "euler" \
            and not scene.pressure.allow_unstable:
        raise _Rule("time.integrator", "euler",
                    "has no stable step with pressure.scheme 'projection' (the one-sweep "
                    "step is forward Euler for the skeleton: on the Section 4.1 columns it "
                    "grew at 0.25 to 1 x Eq. (41), bench/verification/projection_stability.py); "
                    f"use 'symplectic', stable to Eq. (41) {solid_dt_limit(scene):.3e} s "
                    "(pressure.allow_unstable = true to force)")


def check_terzaghi_reference(scene) -> None:
    """What `verify.terzaghi.from_scene` reads (`column_drainage`): a load on the top, one
    drainage time."""
    try:
        column_drainage(scene)
    except ValueError as e:
        raise _Rule("verification.reference", "terzaghi", str(e)) from None


def check_undrained_load(scene) -> None:
    """`initial.undrained_load` is the oedometric state of one step load over a side."""
    key = "initial.undrained_load"
    if len(scene.loads) != 1:
        raise _Rule(key, True, f"needs exactly one [[loads]] (got {len(scene.loads)})")
    load = scene.loads[0]
    if load.history != "ramp" or load.ramp != 0.0 or load.range is not None:
        raise _Rule(key, True, "needs a step load over the whole side (loads[0]: history "
                    "= 'ramp', ramp = 0, no range)")
    if any(scene.gravity) or scene.initial.k0 is not None or \
            scene.initial.water_table is not None:
        raise _Rule(key, True, "needs gravity = [0, 0] and no initial.k0 or water_table")
    if scene.pressure.scheme == "none":
        raise _Rule(key, True, "needs pore water (pressure.scheme is 'none')")
    if len(scene.materials) > 1:
        raise _Rule(key, True, "needs a single material (the column's own modulus)")


def check_tpi_stability(scene) -> None:
    """TPI needs somewhere to drain, and the measured bounds of Eq. (38)-(39): alpha <=
    0.75 and G <= `tpi_gain_limit`."""
    force = "set pressure.allow_unstable = true to force"
    drained = [getattr(scene.boundaries, side).drained_from
               for side in side_planes(scene.dim)
               if getattr(scene.boundaries, side).flow == "drained"]
    if scene.loads and scene.pressure.ponding != "drained" and \
            scene.pressure.explicit_until < min(drained, default=math.inf):
        raise _Rule("pressure.explicit_until", scene.pressure.explicit_until,
                    "TPI loading while no side is drained: Eq. (38) has no storage term, "
                    "so with every side impermeable it fixes p only up to a constant and "
                    "the undrained loading blows up (the terzaghi column at 1.1 ms); run "
                    "the explicit scheme until the first side drains "
                    f"({min(drained, default=math.inf)} s); {force}")
    alpha = scene.pressure.alpha
    if alpha > TPI_ALPHA_MAX:
        raise _Rule("pressure.alpha", alpha,
                    f"TPI is unstable for alpha above {TPI_ALPHA_MAX} at every R measured "
                    f"(bench/verification/stability.py; the paper: above 0.75 at R = 98); {force}")
    dt = tpi_dt(scene)
    gravity = any(g != 0.0 for g in scene.gravity)
    gain, limit = tpi_gain(scene, dt), tpi_gain_limit(alpha, gravity)
    if gain > limit:
        key, value = ("time.dt", dt) if scene.time.dt is not None else \
            ("pressure.R", scene.pressure.R)
        rule = "1.15 (1 - alpha)" if gravity else "min(5 (1 - alpha)^2, 3.6)"
        bench = "bench/verification/tpi_gravity.py" + ("" if gravity else " --no-gravity")
        raise _Rule(key, value,
                    f"TPI gain G = dt gamma_l / (rho k) = {gain:.3g} at dt = {dt:.3e} s "
                    f"is above its stability bound {rule} = {limit:.3g} ({bench}): "
                    f"dt <= {dt * limit / gain:.3e} s; {force}")


def check_symmetry_planes(scene, bounds) -> None:
    """Every box side with `symmetry = true` touches the soil: the seeded particles'
    extent `bounds` ((2, dim): the smallest and largest coordinate over all ranks,
    `psph.geometry.lattice.extent`) comes within one dx of its plane (a lattice touching
    the side has its first row at dx/2). Raises SceneRule naming the side's key, the
    plane and the nearest particle's coordinate. The same verdict on every rank, as
    `bounds` is."""
    dx = scene.particles.dx
    lo, hi = scene.domain.min, scene.domain.max
    for side, (axis, end, _) in side_planes(scene.dim).items():
        if not getattr(scene.boundaries, side).symmetry:
            continue
        plane = (lo, hi)[end][axis]
        near = bounds[end][axis]
        gap = abs(near - plane)
        if gap <= dx * (1 + 1e-9):
            continue
        name = "xyz"[axis]
        where = "no particle at all" if not math.isfinite(near) else \
            f"the nearest at {name} = {near:.6g} m, {gap / dx:.3g} dx away"
        raise _Rule(f"boundaries.{side}.symmetry", True,
                    f"the plane {name} = {plane:g} touches no particle ({where}; dx = "
                    f"{dx:g} m): a symmetry plane needs soil within dx of it")

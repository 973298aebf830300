"""Initial particle state of a scene: of all particles (one process, post-processing) or
of one slab's (each rank seeds its own, so that no rank holds the whole scene), with the
same ids and bits either way. What needs the other ranks (global extrema, the top of each
lattice column) comes through a reducer (psph/geometry/lattice.py); nothing here calls
MPI. The geostatic state is Eq. (2) of Lian et al. (2023), sigma' = sigma + p I, with a
hydrostatic p and the K0 effective stress."""

import math

import numpy as np

from psph.geometry.box import outward_normal, side_planes
from psph.geometry.grids import read_grid
from psph.geometry.lattice import SERIAL, extent, occupancy, seed
from psph.geometry.profiles import read_profile
from psph.geometry.shapes import surface_layer
from psph.physics.material import lame


def soil_positions(scene) -> np.ndarray:
    """Positions of all particles: each block's own lattice, then the domain lattice points
    inside the polygons, meshes and layers (each point once, in lattice order).

    Parameters
    ----------
    scene : Scene
        the validated scene.

    Returns
    -------
    (n, dim) float64 array
        positions (m).
    """
    return seed(scene)[0]


def material_arrays(scene, material: np.ndarray) -> dict[str, np.ndarray]:
    """Per-particle porosity, grain density and conductivity of each particle's material
    (with one material, the scene's scalars in every element).

    Parameters
    ----------
    scene : Scene
        the validated scene.
    material : (n,) array
        each particle's material index.

    Returns
    -------
    dict of str to (n,) float64 array
        "porosity", "rho_s" (kg/m^3) and "k" (m/s).
    """
    mats = scene.material_list
    idx = material.astype(np.int64)
    return {key: np.array([getattr(m, key) for m in mats], float)[idx]
            for key in ("porosity", "rho_s", "k")}


def initial_particles(scene, reducer=SERIAL, slab: tuple[int, float, float] | None = None
                      ) -> dict[str, np.ndarray]:
    """Positions, ids and every field's initial value of the particles in a slab, default
    all of them. Collective over the ranks of `reducer` (each passing its own slab).

    Parameters
    ----------
    scene : Scene
        the validated scene.
    reducer : reducer, optional
        the ranks' reductions (`geometry.lattice.SERIAL`: one process).
    slab : (axis, lo, hi), optional
        the particles with coordinate along axis in [lo, hi) (m).

    Returns
    -------
    dict of str to array
        the fields by name (`state.particles.FIELDS`, SI units).
    """
    dx = scene.particles.dx
    dim = scene.dim
    x, key, material = seed(scene, *(slab or ()), reducer=reducer, material=True)
    bounds = extent(x, reducer)
    n = len(x)
    m = scene.material  # the pore fluid (one for every material)
    per = material_arrays(scene, material)
    poro = per["porosity"]
    vol = np.full(n, dx * dx if dim == 2 else dx * dx * dx)
    # a dry scene (no pore-pressure stages) has empty pores
    rho = (1 - poro) * per["rho_s"] + \
        (poro * m.rho_l if scene.pressure.scheme != "none" else 0.0)
    data = {
        "key": key.astype(float),
        "x": x,
        "poro": poro,
        "poro0": poro.copy(),
        "vol": vol,
        "vol0": vol.copy(),
        "rho": rho,
        "perm": per["k"],
        "material": material,
        "drained_from": np.full(n, math.inf),
        "load_index": np.full(n, -1.0),
        "traction": np.zeros((n, dim)),
        "surface": np.zeros(n),
    }
    for side in side_planes(dim):
        b = getattr(scene.boundaries, side)
        if b.flow == "drained":
            layer = surface_layer(x, side, dx, bounds)
            data["drained_from"][layer] = np.minimum(data["drained_from"][layer],
                                                     b.drained_from)
    for i, load in enumerate(scene.loads):
        if load.side == "surface":
            traction = exposed_faces(scene, x)
            layer = np.any(traction != 0.0, axis=1)
            data["load_index"][layer] = i
            data["traction"][layer] = traction[layer]
            data["surface"][layer] = 1.0
            continue
        layer = surface_layer(x, load.side, dx, bounds)
        if load.range is not None:
            along = x[:, 1] if load.side in ("left", "right") else x[:, 0]
            layer &= (along >= load.range[0]) & (along <= load.range[1])
        data["load_index"][layer] = i
        # the pressure pushes inward over the particle's face, dx (dx^2 in 3D)
        data["traction"][layer] = -outward_normal(load.side, dim) * dx ** (dim - 1)
        data["surface"][layer] = 1.0
    geostatic(scene, data, reducer, bounds)
    if scene.initial.undrained_load:
        undrained_load(scene, data)
    return data


def exposed_faces(scene, x: np.ndarray) -> np.ndarray:
    """The area vectors -n dA (dA = dx^(dim-1)) of the particles' lattice faces that are
    exposed: whose neighbour across the face holds no soil and is not beyond a wall of the
    box (a slip wall is a symmetry plane). A uniform pressure on them is a uniform
    confinement of any shape, exactly: the faces close the particles' union, so the
    tractions balance and leave q inside (`loads.side = "surface"`, Cryer's sphere).

    Parameters
    ----------
    scene : Scene
        the validated scene.
    x : (n, dim) float64 array
        positions (m).

    Returns
    -------
    (n, dim) float64 array
        the area vectors (m^2 in 3D, m per unit thickness in 2D); zero rows inside.
    """
    dx = scene.particles.dx
    dim = scene.dim
    occupied = occupancy(scene)
    lo, hi = np.array(scene.domain.min, float), np.array(scene.domain.max, float)
    walls = {(axis, end) for side, (axis, end, _) in side_planes(dim).items()
             if getattr(scene.boundaries, side).motion != "free"}
    area = dx * dx if dim == 3 else dx
    out = np.zeros((len(x), dim))
    for d in range(dim):
        for sgn, end in ((-1.0, 0), (1.0, 1)):
            nb = x.copy()
            nb[:, d] += sgn * dx
            beyond = nb[:, d] < lo[d] if end == 0 else nb[:, d] > hi[d]
            exposed = ~occupied(nb)
            if (d, end) in walls:
                exposed &= ~beyond
            out[exposed, d] -= sgn * area
    return out


def undrained_load(scene, data: dict[str, np.ndarray]) -> None:
    """The instantaneous undrained response of a laterally confined column to its step
    load q (`initial.undrained_load`): the pore water and the skeleton share the strain,
    p0 = q / (1 + n M / K_l) with M the plane-strain constrained modulus, sigma' = -(q - p0)
    along the load and nu / (1 - nu) of that across it (in plane and out of plane). The
    reference of Terzaghi's problem starts from this state (psph/verify/terzaghi.py).

    Parameters
    ----------
    scene : Scene
        the validated scene (its first load is the step load, Pa).
    data : dict of str to array
        the fields; "stress" (Pa), "p" and "p_prev" (Pa) are set.
    """
    m = scene.material
    load = scene.loads[0]
    lam, shear = lame(m.E, m.nu)
    modulus = lam + 2 * shear
    p0 = load.pressure / (1.0 + m.porosity * modulus / m.K_l)
    along = -(load.pressure - p0)
    n = len(data["key"])
    stress = np.zeros((n, 4))
    axis = 0 if load.side in ("left", "right") else 1
    stress[:, :3] = lam / modulus * along
    stress[:, axis] = along
    data["stress"] = stress
    data["p"] = np.full(n, p0)
    data["p_prev"] = data["p"].copy()


def table_elevation(table, x: np.ndarray) -> np.ndarray:
    """Elevation of a water table given as a level (m), a phreatic profile ([[x, z], ...]
    or a CSV path, psph/geometry/profiles.py) or, in 3D, an elevation grid
    (psph/geometry/grids.py): a profile linear between its points and held at its end
    values beyond them, a grid bilinear.

    Parameters
    ----------
    table : float, list or str
        the level (m), the profile's points or CSV path, or the grid's path.
    x : (n, dim) float64 array
        positions (m).

    Returns
    -------
    (n,) float64 array
        the table's elevation above each position (m).
    """
    if isinstance(table, (int, float)):
        return np.full(len(x), float(table))
    if x.shape[1] == 3:
        return read_grid(table).at(x[:, 0], x[:, 1])
    points = read_profile(table)
    return np.interp(x[:, 0], points[:, 0], points[:, 1])


def geostatic(scene, data: dict[str, np.ndarray], reducer=SERIAL,
              bounds: np.ndarray | None = None) -> None:
    """Hydrostatic pore pressure below `initial.water_table` (an elevation, a phreatic
    profile, or "surface": zero at the centres of each column's top particle) and the K0
    effective stress
    (sigma'_v from the weight of the soil above, sigma'_h = sigma'_zz = K0 sigma'_v), in
    place. The ground surface above a particle is the top of its particle column.

    Total vertical stress: the weight of the soil above in the particle's lattice column,
    sigma_v = -g integral rho dz (tension positive) with each particle's own mixture
    density over its dx and half of its own (`overburden`); in a column of one density
    this is -rho g d at depth d, computed so. Eq. (2) sigma' = sigma + p I gives
    sigma'_v = sigma_v + p.

    Parameters
    ----------
    scene : Scene
        the validated scene.
    data : dict of str to array
        the fields of all particles or of one slab's; "p", "p_prev" and "stress" (Pa)
        are set.
    reducer : reducer, optional
        the ranks' reductions: the column tops of all particles.
    bounds : (2, dim) float64 array, optional
        the smallest and largest x of all particles (m; `lattice.extent`).
    """
    init = scene.initial
    if init.water_table is None and init.k0 is None:
        return
    n = len(data["key"])
    x = data["x"]
    vz = x.shape[1] - 1  # the vertical axis: y in 2D, z in 3D
    g = -scene.gravity[vz]
    dx = scene.particles.dx
    # lattice columns: x = x_min + k dx (rounding x / dx itself would merge neighbouring
    # columns, whose centres sit at half-integers, and shift p by rho_l g dx); in 3D the
    # columns of the (x, y) lattice
    if bounds is None:
        bounds = extent(x, reducer)
    x_min, x_max = bounds[0, :vz], bounds[1, :vz]
    k = np.round((x[:, :vz] - x_min) / dx).astype(np.int64)
    shape = tuple(int(m) for m in np.round((x_max - x_min) / dx).astype(np.int64) + 1)
    column = k[:, 0] if vz == 1 else np.ravel_multi_index(k.T, shape)
    top = np.full(int(np.prod(shape)), -np.inf)
    np.maximum.at(top, column, x[:, vz])
    top = reducer.max(top)
    depth = top[column] + 0.5 * dx - x[:, vz]
    if init.water_table is not None:
        head = depth - 0.5 * dx if init.water_table == "surface" \
            else table_elevation(init.water_table, x) - x[:, vz]
        p = scene.material.rho_l * g * np.maximum(head, 0.0)
        if scene.pressure.drained_boundary == "layer":
            p = np.where(np.isfinite(data["drained_from"]) & (data["drained_from"] <= 0.0),
                         0.0, p)
        data["p"] = p
        data["p_prev"] = p.copy()
    if init.k0 is not None:
        sigma_v = -data["rho"] * g * depth
        if len(scene.material_list) > 1:
            sigma_v -= g * overburden(data["rho"], x[:, vz], column, len(top), dx, reducer)
        sigma_v += data.get("p", np.zeros(n))
        stress = np.zeros((n, 4 if vz == 1 else 6))
        horizontal = init.k0 * sigma_v
        for c in range(3):
            stress[:, c] = sigma_v if c == vz else horizontal
        data["stress"] = stress


def overburden(rho: np.ndarray, y: np.ndarray, column: np.ndarray, n_columns: int,
               dx: float, reducer=SERIAL) -> np.ndarray:
    """The part of the column's weight per area above each particle (kg/m^2) that
    rho_i d_i misses: sum over the particles j above i in its lattice column of
    (rho_j - rho_i) dx, so that rho_i d_i + this = the integral of rho over the column
    from its top to particle i's centre (each particle above over its dx, i's own over
    dx / 2; a gap in the column counts with rho_i, as the single-density formula does).
    Exactly 0 in a column of one density.

    Each column's running sum goes from its top down, particle by particle (a padded 2D
    cumulative sum), the same additions in the same order on any number of ranks: with
    slabs cut along x a column lies on one rank; with slabs cut along y (in rank order
    upward) each rank continues the running sums the ranks above it hand down, one
    reduction a rank (set-up only).

    Parameters
    ----------
    rho : (n,) float64 array
        mixture density (kg/m^3).
    y : (n,) float64 array
        vertical coordinate (m).
    column : (n,) int64 array
        each particle's lattice column.
    n_columns : int
        number of columns.
    dx : float
        particle spacing (m).
    reducer : reducer, optional
        the ranks' reductions.

    Returns
    -------
    (n,) float64 array
        the missing weight per area divided by g (kg/m^2).
    """
    ref = np.full(n_columns, -np.inf)
    np.maximum.at(ref, column, rho)
    ref = reducer.max(ref)  # one reference density a column, so equal rho give d = 0
    d = rho - ref[column]
    order = np.lexsort((-y, column))  # by column, each from its top down
    cols, slot, counts = np.unique(column[order], return_inverse=True, return_counts=True)
    first = np.concatenate(([0], np.cumsum(counts)[:-1]))
    pos = np.arange(len(order)) - first[slot]  # particles above, on this rank
    grid = np.zeros((len(cols), (counts.max() if len(counts) else 0) + 1))
    running = np.zeros(2 * n_columns)  # sum of d and count above this rank, per column
    count_above = np.zeros(len(cols))
    for r in range(reducer.size - 1, -1, -1):
        if r == reducer.rank:
            grid[:, 0] = running[cols]
            count_above = running[n_columns + cols]
            grid[slot, pos + 1] = d[order]
            np.cumsum(grid, axis=1, out=grid)
            mine = running.copy()
            mine[cols] = grid[np.arange(len(cols)), counts]
            mine[n_columns + cols] += counts
        else:
            mine = np.zeros(2 * n_columns)
        if reducer.size > 1:
            running = reducer.sum(mine) if r > 0 else running
    above = np.empty_like(d)
    above[order] = grid[slot, pos]  # sum of d over the particles above
    count = np.empty_like(d)
    count[order] = pos + count_above[slot]
    return (above - count * d) * dx

"""Mirror ghost particles for walls (free-slip and fixed), as in Bui et al. (2008).

A wall is a plane x[axis] = pos with the soil on the side `sign` (+1: soil at larger x).
Ghosts mirror the real particles (owned and halo) within `reach` (= 2h) of a wall: position
mirrored; velocity and acceleration with the normal component reversed (free slip) or both
reversed (fixed, no slip), and `v_slip` with the free-slip mirror on every wall (the
stretching rates take it, see `interactions.py`); effective stress mirrored (shear
component reversed on a free-slip wall, kept on a fixed one so that the wall resists
tangential motion), except for its wall-normal component (below); porosity, volume,
density and permeability copied; pore pressure copied plus the hydrostatic difference
rho_l b.(x_ghost - x_real), so that the total head p + psi of Eq. (25) is mirrored and a
wall is impermeable also under gravity; on a drained wall (`Walls.drained`) the pore
pressure is mirrored antisymmetrically, p_ghost = -p_real, so that p = 0 on the wall
plane itself (as across the drained planes of `images.py`).
Particles near two walls of different axes also get a corner ghost mirrored across both,
and in 3D, near three, one mirrored across all three.

The wall-normal total stress sigma_nn = sigma'_nn - p (Eq. 2) of a ghost is the real
particle's plus the weight of the soil between them, -rho_j b.(x_ghost - x_real): the
continuation of the equilibrium gradient d sigma_nn / dn = -rho b_n (Eq. 6 at rest), so
that a geostatic stress, linear in depth, stays linear across the wall and the pair sum of
Eq. (26) balances the weight of the rows next to the wall. The weight only on a wall
that carries the soil, the body force pointing into it (a floor); on a lid, or a wall the
body force points away from, the total stress is mirrored (the continuation would be a
tension that holds the soil up). sigma'_nn follows by Eq. (2)
with the ghost's own p. A plain mirror (sigma'_nn copied) puts a kink in it at the wall:
the bottom row of a column at rest then lacks (rho - rho_l) g dx of support, sinks by
2.7 m/s^2 at t = 0, and the column settles into the lattice's odd-even (zig-zag) mode of
sigma', which the pair-symmetric Eq. (26) cannot see and so never damps (1.5 % of the base
stress in a column of one density).

The kernels take the fields as a `bundles.WallFields` and the walls as a `bundles.Walls`.
"""

import numba as nb


@nb.njit(cache=True)
def _mirror(src, dst, axis, pos, fixed, drained, f, head_b, body):
    """Row dst of the fields f (`bundles.WallFields`) = the mirror image of row src across
    the wall x[axis] = pos (fixed: no slip; drained: p antisymmetric); module docstring."""
    x, v, v_slip, stress, p, p_prev, poro, vol, rho, perm, acc, key = f
    three = x.shape[1] == 3
    x[dst, 0] = x[src, 0]
    x[dst, 1] = x[src, 1]
    if three:
        x[dst, 2] = x[src, 2]
    x[dst, axis] = 2.0 * pos - x[src, axis]
    for d in range(3 if three else 2):
        if d == axis or fixed:
            v[dst, d] = -v[src, d]
            acc[dst, d] = -acc[src, d]
        else:
            v[dst, d] = v[src, d]
            acc[dst, d] = acc[src, d]
        v_slip[dst, d] = -v_slip[src, d] if d == axis else v_slip[src, d]
    stress[dst, 0] = stress[src, 0]
    stress[dst, 1] = stress[src, 1]
    stress[dst, 2] = stress[src, 2]
    # free slip: the shear components on the wall's plane reversed, so a real-ghost pair
    # carries no shear traction; fixed: kept, so the wall's shear reaction resists sliding
    # along it. 2D: xy; 3D: xy, yz, zx, those with the wall's normal axis
    stress[dst, 3] = stress[src, 3] if (fixed or axis == 2) else -stress[src, 3]
    if three:
        stress[dst, 4] = stress[src, 4] if (fixed or axis == 0) else -stress[src, 4]
        stress[dst, 5] = stress[src, 5] if (fixed or axis == 1) else -stress[src, 5]
    if drained:
        p[dst] = -p[src]
        p_prev[dst] = -p_prev[src]
    else:
        dp = head_b[0] * (x[dst, 0] - x[src, 0]) + head_b[1] * (x[dst, 1] - x[src, 1])
        if three:
            dp += head_b[2] * (x[dst, 2] - x[src, 2])
        p[dst] = p[src] + dp
        p_prev[dst] = p_prev[src] + dp
    # the wall-normal total stress continued with its equilibrium gradient -rho b (module
    # docstring); the effective one with the ghost's pore pressure (Eq. 2). The weight
    # only where the wall carries the soil (the body force points into it: weight < 0):
    # under a lid the continuation would be a tension that holds the soil up
    weight = min(-rho[src] * body[axis] * (x[dst, axis] - x[src, axis]), 0.0)
    stress[dst, axis] += weight + p[dst] - p[src]
    poro[dst] = poro[src]
    vol[dst] = vol[src]
    rho[dst] = rho[src]
    perm[dst] = perm[src]
    key[dst] = key[src]


@nb.njit(cache=True)
def make_ghosts(n_real, cap, reach, key_stride, walls, f, head_b, body, ghosts):
    """Write the wall ghosts of the real rows 0..n_real-1 at rows n_real, n_real+1, ...
    (module docstring). 2D or 3D by f.x: near two walls of different axes a particle also
    gets the ghost mirrored across both (an edge), near three (3D) the one across all
    three (a corner).

    Parameters
    ----------
    n_real : int
        real rows (owned and halo).
    cap : int
        rows of the arrays.
    reach : float
        depth of the ghost layer (m, 2h): the particles within it of a wall are mirrored.
    key_stride : float
        at least the number of particle ids: a ghost's key is key + key_stride * (1 +
        code), the code unique per wall, edge and corner, so that the neighbour order is
        the same on any number of ranks.
    walls : bundles.Walls
        the plane walls; walls.drained[w]: the wall's pore pressure is mirrored
        antisymmetrically (p = 0 on it).
    f : bundles.WallFields
        every row's fields; the ghosts' rows are written. f.v_slip: rows 0..n_real-1 get
        v, the ghosts its free-slip mirror (f.v itself may be passed when no wall is
        fixed).
    head_b : (dim,) float array
        rho_l times the body force (N/m^3), for the hydrostatic pressure shift (zero in a
        scene without pore pressure).
    body : (dim,) float array
        the body force b (m/s^2), for the weight between a particle and its ghost in the
        wall-normal stress.
    ghosts : bundles.GhostSources
        written for each ghost g: src[g], the real row it mirrors (corner ghosts too), for
        fields that are mirrored again later (the search direction of the pressure
        solve), and sign[g], the sign that carries a pressure increment to it (-1 across
        a drained wall).

    Returns
    -------
    int
        the number of ghosts, or -1 if `cap` rows are not enough.
    """
    wall_axis, wall_pos, wall_sign, wall_fixed, wall_drained = walls
    x, v, v_slip, key = f.x, f.v, f.v_slip, f.key
    src, src_sign = ghosts
    nw = wall_axis.shape[0]
    three = x.shape[1] == 3
    for j in range(n_real):
        v_slip[j, 0] = v[j, 0]
        v_slip[j, 1] = v[j, 1]
        if three:
            v_slip[j, 2] = v[j, 2]
    g = n_real
    for j in range(n_real):
        for w in range(nw):
            dw = wall_sign[w] * (x[j, wall_axis[w]] - wall_pos[w])
            if dw < 0.0 or dw >= reach:
                continue
            if g >= cap:
                return -1
            _mirror(j, g, wall_axis[w], wall_pos[w], wall_fixed[w], wall_drained[w], f,
                    head_b, body)
            key[g] = key[j] + key_stride * (1 + w)
            src[g] = j
            src_sign[g] = -1.0 if wall_drained[w] else 1.0
            gg = g  # the ghost across w: the edges across w and a second wall mirror it
            g += 1
            for w2 in range(w + 1, nw):
                if wall_axis[w2] == wall_axis[w]:
                    continue
                d2 = wall_sign[w2] * (x[j, wall_axis[w2]] - wall_pos[w2])
                if d2 < 0.0 or d2 >= reach:
                    continue
                if g >= cap:
                    return -1
                _mirror(gg, g, wall_axis[w2], wall_pos[w2], wall_fixed[w2], wall_drained[w2],
                        f, head_b, body)
                key[g] = key[j] + key_stride * (1 + nw + w * nw + w2)
                src[g] = j
                src_sign[g] = src_sign[gg] * (-1.0 if wall_drained[w2] else 1.0)
                ge = g  # the edge: a corner mirrors it across a third wall
                g += 1
                for w3 in range(w2 + 1, nw):
                    if wall_axis[w3] == wall_axis[w] or wall_axis[w3] == wall_axis[w2]:
                        continue
                    d3 = wall_sign[w3] * (x[j, wall_axis[w3]] - wall_pos[w3])
                    if d3 < 0.0 or d3 >= reach:
                        continue
                    if g >= cap:
                        return -1
                    _mirror(ge, g, wall_axis[w3], wall_pos[w3], wall_fixed[w3],
                            wall_drained[w3], f, head_b, body)
                    key[g] = key[j] + key_stride * (1 + nw + nw * nw + (w * nw + w2) * nw + w3)
                    src[g] = j
                    src_sign[g] = src_sign[ge] * (-1.0 if wall_drained[w3] else 1.0)
                    g += 1
    return g - n_real


@nb.njit(cache=True)
def wall_contact(n_owned, x, v, u, wall_axis, wall_pos, wall_sign):
    """No penetration: an owned particle found beyond a wall plane is reflected back into
    the soil and loses its velocity into the wall. Ghost stresses keep particles off the
    walls in compression; a particle in tension (at the Drucker-Prager apex, Eq. 14) is
    pulled toward its own mirror image, and this stops it.

    Parameters
    ----------
    n_owned : int
        the owned rows, the particles put back.
    x, v, u : (cap, dim) float arrays
        positions (m), velocities (m/s) and displacements (m), changed on the rows moved.
    wall_axis, wall_pos, wall_sign : arrays
        the walls x[axis] = pos (m) with the soil on the side `sign` (as `bundles.Walls`).

    Returns
    -------
    int
        the number of reflections (a particle beyond two walls counts twice).
    """
    moved = 0
    for i in range(n_owned):
        for w in range(wall_axis.shape[0]):
            a = wall_axis[w]
            d = wall_sign[w] * (x[i, a] - wall_pos[w])
            if d < 0.0:
                shift = -2.0 * d * wall_sign[w]
                x[i, a] += shift
                u[i, a] += shift
                if wall_sign[w] * v[i, a] < 0.0:
                    v[i, a] = 0.0
                moved += 1
    return moved

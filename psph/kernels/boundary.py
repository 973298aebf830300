"""Boundary particles of rigid polylines: their state each step, and the no-penetration
safety net (2D and 3D).

The state follows the generalized wall boundary condition of Adami, Hu & Adams (2012,
J. Comput. Phys. 231, 7057), with the conventions of the plane mirror ghosts
(`ghosts.py`). For a boundary particle b with unit normal n (into the soil), over the soil
particles j (rows < n_real) within 2h, with W_bj of Eq. (21):

  Shepard average   f~_b = sum_j f_j W_bj / sum_j W_bj          (velocity, stress, n, rho, k)
  velocity          fixed:  v_b = -v~_b   (no slip: the wall velocity 0 is the mean of
                                           v~ and v_b, Adami Eq. 22 with v_w = 0)
                    slip:   v_b = v~_b - 2 (v~_b . n) n   (normal reversed, tangent kept)
  v_slip            the slip mirror on every polyline (the stretching rates and the
                    artificial viscosity take it, as on plane ghosts: `interactions.py`)
  pore pressure     impermeable: p_b = sum_j (p_j + rho_l b . (x_b - x_j)) W_bj / sum W,
                    the total head p + psi of Eq. (25) extended into the wall (Adami Eq. 27
                    with the wall at rest), so that the wall is impermeable under gravity;
                    drained: p_b = -p~_b (antisymmetric: p = 0 on the line)
  effective stress  sigma'~_b, with its shear sigma'_tn in the wall's frame (t, n) kept on
                    a fixed wall (it resists sliding) and reversed on a slip wall (the pair
                    stress of Eq. 26, (sigma_a + sigma_b)/2, carries no shear across it)
  friction          Coulomb, per boundary particle, from the averaged stress of the soil in
                    front of it: the limit is tau_max = tan(phi_b) max(-sigma'~_nn, 0). If
                    |sigma'~_tn| <= tau_max the wall sticks (as a fixed wall); else it
                    slides: the velocity as on a slip wall, and sigma'_tn,b = 2 s tau_max -
                    sigma'~_tn (s = sign sigma'~_tn), so that the traction the pair stress
                    of Eq. (26) carries across the wall, (sigma'~_tn + sigma'_tn,b) / 2, is
                    the Coulomb limit s tau_max. Both branches meet at |sigma'~_tn| =
                    tau_max; tau_max = 0 is the slip wall.
  acceleration      as the velocity (the div(k dv/dt) term of Eq. 25)

A boundary particle without soil within 2h interacts with no soil either; it gets v = 0,
p = 0, sigma' = 0.

The kernels take their arrays in bundles (`bundles.py`): the store's rows of boundary
particles (`BoundaryRows`), the scene's boundary particles (`BoundaryPoints`), the fields
(`WallFields`, `ContactFields`) and the cell lists (`CellList`, `ContactGrid`).
"""

import math

import numba as nb

from psph.kernels.spline import w_cubic

MOTION_FIXED = 0
MOTION_SLIP = 1
MOTION_FRICTION = 2


@nb.njit(cache=True)
def _shear_frame(n0, n1):
    """Tangent t = (n1, -n0) and S = t n^T + n t^T (xx, yy, xy) of the wall frame."""
    t0 = n1
    t1 = -n0
    return t0, t1, 2.0 * t0 * n0, 2.0 * t1 * n1, t0 * n1 + t1 * n0


@nb.njit(cache=True)
def boundary_state(n_real, rows, pts, f, head_b, cells, h):
    """State of the boundary rows (see the module docstring), and v copied into v_slip on
    the real rows. The neighbour loop visits the 3 x 3 cells around each boundary
    particle in a fixed order and a cell's particles in key order (`neighbours.py`): the
    sums are the same on any number of ranks as long as every soil particle within 2h of
    the boundary particle is a real row (halo of 4h).

    Parameters
    ----------
    n_real : int
        real rows (owned and halo): the soil.
    rows : bundles.BoundaryRows
        the boundary rows first..first+n-1; row first + r holds the polyline boundary
        particle src[r].
    pts : bundles.BoundaryPoints
        the polylines' boundary particles: their polyline's motion, tan_phi and drained,
        and their unit normal into the soil (foot, weight_dv, half_weight unused).
    f : bundles.WallFields
        every row's fields (2D); the boundary rows' velocity, v_slip (m/s), effective
        stress (Pa), p, p_prev (Pa), porosity, density (kg/m^3), conductivity (m/s) and
        acceleration (m/s^2) are written (vol and key unused).
    head_b : (2,) float array
        rho_l times the body force (N/m^3), for the hydrostatic pressure shift.
    cells : bundles.CellList
        the step's cell lists of side 2h over every row.
    h : float
        smoothing length (m).
    """
    first, n_b, src = rows
    motion, tan_phi, drained, normal = pts.motion, pts.tan_phi, pts.drained, pts.normal
    x, v, v_slip, stress, p, p_prev = f.x, f.v, f.v_slip, f.stress, f.p, f.p_prev
    poro, rho, perm, acc = f.poro, f.rho, f.perm, f.acc
    cell_of, cell_start, order, ncell = cells
    for j in range(n_real):
        v_slip[j, 0] = v[j, 0]
        v_slip[j, 1] = v[j, 1]
    ncx = ncell[0]
    ncy = ncell[1]
    support2 = 4.0 * h * h
    for r in range(n_b):
        b = first + r
        k = src[r]
        c = cell_of[b]
        cx = c % ncx
        cy = c // ncx
        ws = 0.0
        sv0 = sv1 = sa0 = sa1 = 0.0
        sp = spp = 0.0
        s0 = s1 = s2 = s3 = 0.0
        sn = sr = sk = 0.0
        for oy in range(-1, 2):
            ny = cy + oy
            if ny < 0 or ny >= ncy:
                continue
            for ox in range(-1, 2):
                nx = cx + ox
                if nx < 0 or nx >= ncx:
                    continue
                nc = ny * ncx + nx
                for s in range(cell_start[nc], cell_start[nc + 1]):
                    j = order[s]
                    if j >= n_real:
                        continue
                    d0 = x[b, 0] - x[j, 0]
                    d1 = x[b, 1] - x[j, 1]
                    r2 = d0 * d0 + d1 * d1
                    if r2 >= support2:
                        continue
                    w = w_cubic(math.sqrt(r2), h)
                    ws += w
                    sv0 += w * v[j, 0]
                    sv1 += w * v[j, 1]
                    sa0 += w * acc[j, 0]
                    sa1 += w * acc[j, 1]
                    if drained[k]:
                        sp -= w * p[j]
                        spp -= w * p_prev[j]
                    else:
                        dp = head_b[0] * d0 + head_b[1] * d1
                        sp += w * (p[j] + dp)
                        spp += w * (p_prev[j] + dp)
                    s0 += w * stress[j, 0]
                    s1 += w * stress[j, 1]
                    s2 += w * stress[j, 2]
                    s3 += w * stress[j, 3]
                    sn += w * poro[j]
                    sr += w * rho[j]
                    sk += w * perm[j]
        if ws == 0.0:
            v[b, 0] = v[b, 1] = v_slip[b, 0] = v_slip[b, 1] = 0.0
            acc[b, 0] = acc[b, 1] = 0.0
            p[b] = p_prev[b] = 0.0
            for q in range(4):
                stress[b, q] = 0.0
            poro[b] = 0.5
            rho[b] = 1.0
            perm[b] = 0.0
            continue
        iw = 1.0 / ws
        n0 = normal[k, 0]
        n1 = normal[k, 1]
        vt0 = sv0 * iw
        vt1 = sv1 * iw
        vn = vt0 * n0 + vt1 * n1
        at0 = sa0 * iw
        at1 = sa1 * iw
        an = at0 * n0 + at1 * n1
        sxx = s0 * iw
        syy = s1 * iw
        sxy = s3 * iw
        t0, t1, m_xx, m_yy, m_xy = _shear_frame(n0, n1)
        s_nn = n0 * (sxx * n0 + sxy * n1) + n1 * (sxy * n0 + syy * n1)
        s_tn = t0 * (sxx * n0 + sxy * n1) + t1 * (sxy * n0 + syy * n1)
        mode = motion[k]
        if mode == MOTION_FRICTION:
            cap = tan_phi[k] * max(-s_nn, 0.0)
            if abs(s_tn) <= cap:
                mode = MOTION_FIXED
            else:
                target = 2.0 * math.copysign(cap, s_tn) - s_tn
                sxx += (target - s_tn) * m_xx
                syy += (target - s_tn) * m_yy
                sxy += (target - s_tn) * m_xy
        elif mode == MOTION_SLIP:  # shear reversed: target - s_tn = -2 s_tn
            sxx -= 2.0 * s_tn * m_xx
            syy -= 2.0 * s_tn * m_yy
            sxy -= 2.0 * s_tn * m_xy
        v_slip[b, 0] = vt0 - 2.0 * vn * n0
        v_slip[b, 1] = vt1 - 2.0 * vn * n1
        if mode == MOTION_FIXED:
            v[b, 0] = -vt0
            v[b, 1] = -vt1
            acc[b, 0] = -at0
            acc[b, 1] = -at1
        else:
            v[b, 0] = v_slip[b, 0]
            v[b, 1] = v_slip[b, 1]
            acc[b, 0] = at0 - 2.0 * an * n0
            acc[b, 1] = at1 - 2.0 * an * n1
        stress[b, 0] = sxx
        stress[b, 1] = syy
        stress[b, 2] = s2 * iw
        stress[b, 3] = sxy
        p[b] = sp * iw
        p_prev[b] = spp * iw
        poro[b] = sn * iw
        rho[b] = sr * iw
        perm[b] = sk * iw


@nb.njit(cache=True)
def boundary_contact(n_owned, f, rows, pts, grid, cell_size, h, reach, rho_water=0.0):
    """No penetration (safety net): an owned particle found on the wall side of the line
    (in 3D the tangent plane) of its nearest boundary particle (within 2h, in the cell
    lists of this step) is reflected back across it, (x - foot) . n -> -(x - foot) . n,
    and loses its velocity into the wall, as `ghosts.wall_contact` does for planes. 2D
    or 3D by x (the 2D arithmetic in its own order).

    The Coulomb friction of a particle's weight (`weight_friction` walls): a particle
    within `reach` of that plane (after the reflection) loses min(|v_t|, s weight_dv[k])
    of its tangential velocity v_t = v - (v . n) n, with weight_dv[k] = tan(phi_b) g_n dt
    of its boundary particle k (0: no such friction) and s = 1 - max(-sigma'_nn, 0) /
    (rho half_weight[k]) the share of its weight its own normal stress does not carry
    (half_weight = g_n dx / 2: none once sigma'_nn holds half a particle's weight, which
    the wall's stress-based limit then counts, `boundary_3d`; all of it at the
    Drucker-Prager apex, the film of docs/vv/collapse_3d.md). In a saturated scene
    (rho_water = rho_l; 0 when dry) both count the buoyant weight, rho - rho_l: the
    effective stress carries it and the Coulomb friction acts on it, the pore pressure
    carries the water's share (a hydrostatic p; above a water table, p = 0, this
    undercounts); dv is then scaled by (rho - rho_l) / rho.

    Parameters
    ----------
    n_owned : int
        the owned rows, the particles put back.
    f : bundles.ContactFields
        every row's positions (m), velocities (m/s) and displacements (m), changed on the
        owned rows moved, and the effective stress (Pa) and density (kg/m^3) of the
        weight friction.
    rows : bundles.BoundaryRows
        the boundary rows first..first+n-1; row first + r holds the boundary particle
        src[r].
    pts : bundles.BoundaryPoints
        the boundary particles' unit normals into the soil, a point `foot` of their wall
        (m), weight_dv (m/s) and half_weight (m^2/s^2) of the weight friction (motion,
        tan_phi, drained unused).
    grid : bundles.ContactGrid
        the step's cell lists of side `cell_size` over every row.
    cell_size : float
        the cells' side (m, at least 2h).
    h : float
        smoothing length (m).
    reach : float
        distance from the wall (m) within which a particle has the weight friction.
    rho_water : float
        rho_l (kg/m^3) in a saturated scene, 0 in a dry one.

    Returns
    -------
    int
        the number of particles moved.
    """
    x, v, u, stress, rho = f
    first, n_b, src = rows
    normal, foot, weight_dv, half_weight = pts.normal, pts.foot, pts.weight_dv, pts.half_weight
    origin, grid_lo, ncell, cell_start, order = grid
    three = x.shape[1] == 3
    ncx = ncell[0]
    ncy = ncell[1]
    ncz = ncell[2] if three else 1
    oz_lo = -1 if three else 0
    oz_hi = 2 if three else 1
    last = first + n_b
    moved = 0
    for i in range(n_owned):
        cx = int(math.floor((x[i, 0] - origin[0]) / cell_size)) - grid_lo[0]
        cy = int(math.floor((x[i, 1] - origin[1]) / cell_size)) - grid_lo[1]
        cz = int(math.floor((x[i, 2] - origin[2]) / cell_size)) - grid_lo[2] if three else 0
        best = -1
        best_r2 = 4.0 * h * h
        for oz in range(oz_lo, oz_hi):
            nz = cz + oz
            if nz < 0 or nz >= ncz:
                continue
            for oy in range(-1, 2):
                ny = cy + oy
                if ny < 0 or ny >= ncy:
                    continue
                for ox in range(-1, 2):
                    nx = cx + ox
                    if nx < 0 or nx >= ncx:
                        continue
                    nc = (nz * ncy + ny) * ncx + nx
                    for s in range(cell_start[nc], cell_start[nc + 1]):
                        b = order[s]
                        if b < first or b >= last:
                            continue
                        d0 = x[i, 0] - x[b, 0]
                        d1 = x[i, 1] - x[b, 1]
                        r2 = d0 * d0 + d1 * d1
                        if three:
                            d2 = x[i, 2] - x[b, 2]
                            r2 += d2 * d2
                        if r2 < best_r2:
                            best_r2 = r2
                            best = b
        if best < 0:
            continue
        k = src[best - first]
        d = (x[i, 0] - foot[k, 0]) * normal[k, 0] + (x[i, 1] - foot[k, 1]) * normal[k, 1]
        if three:
            d += (x[i, 2] - foot[k, 2]) * normal[k, 2]
        if d < 0.0:
            vn = 0.0
            for q in range(x.shape[1]):
                x[i, q] -= 2.0 * d * normal[k, q]
                u[i, q] -= 2.0 * d * normal[k, q]
                vn += v[i, q] * normal[k, q]
            if vn < 0.0:
                for q in range(x.shape[1]):
                    v[i, q] -= vn * normal[k, q]
            moved += 1
            d = -d
        if weight_dv[k] > 0.0 and d < reach:
            # the share of the weight the particle's own normal stress does not carry:
            # all of it at the Drucker-Prager apex (sigma' = 0), none once sigma'_nn
            # holds half a particle's weight, rho g_n dx / 2 (the wall's stress-based
            # Coulomb limit then counts its weight: `boundary_3d`)
            snn = _normal_stress(stress, i, normal, k)
            buoyant = rho[i] - rho_water
            if buoyant > 0.0:
                share = 1.0 - max(-snn, 0.0) / (buoyant * half_weight[k])
                if share > 0.0:
                    _coulomb_weight(v, i, normal, k, share * weight_dv[k] * (buoyant / rho[i]))
    return moved


@nb.njit(cache=True, inline="always")
def _normal_stress(stress, i, normal, k):
    """n . sigma'_i . n of row i on the normal of boundary source k (2D: xx, yy, zz, xy;
    3D: xx, yy, zz, xy, yz, zx)."""
    n0 = normal[k, 0]
    n1 = normal[k, 1]
    if normal.shape[1] == 2:
        return (stress[i, 0] * n0 * n0 + stress[i, 1] * n1 * n1
                + 2.0 * stress[i, 3] * n0 * n1)
    n2 = normal[k, 2]
    return (stress[i, 0] * n0 * n0 + stress[i, 1] * n1 * n1 + stress[i, 2] * n2 * n2
            + 2.0 * (stress[i, 3] * n0 * n1 + stress[i, 4] * n1 * n2
                     + stress[i, 5] * n2 * n0))


@nb.njit(cache=True, inline="always")
def _coulomb_weight(v, i, normal, k, dv):
    """v_t of row i reduced by min(|v_t|, dv) along itself (`boundary_contact`)."""
    dim = v.shape[1]
    vn = 0.0
    for q in range(dim):
        vn += v[i, q] * normal[k, q]
    vt2 = 0.0
    for q in range(dim):
        vt = v[i, q] - vn * normal[k, q]
        vt2 += vt * vt
    if vt2 == 0.0:
        return
    vt = math.sqrt(vt2)
    f = min(vt, dv) / vt
    for q in range(dim):
        v[i, q] -= f * (v[i, q] - vn * normal[k, q])


@nb.njit(cache=True)
def near_box(bx, candidates, x, n_real, margin, bbox, out):
    """out[:m] = the candidates k (in their order) whose bx[k] lies within `margin` of
    the bounding box of x[:n_real].

    Parameters
    ----------
    bx : (m_b, dim) float array
        the boundary particles' positions (m).
    candidates : int array
        the boundary particles to test, in the order kept.
    x : (cap, dim) float array
        the store's positions (m).
    n_real : int
        rows of x in the box (owned and halo).
    margin : float
        how far outside the box a boundary particle may lie (m).
    bbox : (2, dim) float array
        receives the box's lower and upper corners (m).
    out : int array
        receives the selected boundary particles.

    Returns
    -------
    int
        their number m (0 without rows).
    """
    dim = x.shape[1]
    if n_real == 0:
        return 0
    for d in range(dim):
        bbox[0, d] = x[0, d]
        bbox[1, d] = x[0, d]
    for i in range(1, n_real):
        for d in range(dim):
            bbox[0, d] = min(bbox[0, d], x[i, d])
            bbox[1, d] = max(bbox[1, d], x[i, d])
    m = 0
    for r in range(candidates.shape[0]):
        k = candidates[r]
        inside = True
        for d in range(dim):
            if bx[k, d] < bbox[0, d] - margin or bx[k, d] > bbox[1, d] + margin:
                inside = False
        if inside:
            out[m] = k
            m += 1
    return m


@nb.njit(cache=True)
def place_rows(first, n_b, src, bx, bkey, cell_volume, x, key, vol):
    """Positions, sort keys and volumes of the selected boundary particles at rows
    first..first+n_b-1 of the store (2D or 3D by bx).

    Parameters
    ----------
    first, n_b : int
        the first row and the number of rows.
    src : int array
        src[r]: the boundary particle of row first + r.
    bx : (m_b, dim) float array
        the boundary particles' positions (m).
    bkey : float array
        their sort keys.
    cell_volume : float
        their volume, dx^dim (m^3; m^2 in 2D).
    x, key, vol : arrays
        the store's positions (m), keys and volumes, written at the rows.
    """
    for r in range(n_b):
        k = src[r]
        for d in range(bx.shape[1]):
            x[first + r, d] = bx[k, d]
        key[first + r] = bkey[k]
        vol[first + r] = cell_volume

"""Boundary particles of rigid surfaces in 3D: their state each step, the 3D form of
`boundary.py` (polylines in 2D; its `boundary_contact` serves both).

As in 2D (Adami, Hu & Adams 2012, with the plane ghosts' conventions), a boundary
particle b with unit normal n (into the soil) takes the Shepard averages f~_b of the soil
particles j (rows < n_real) within 2h: velocity and acceleration (fixed: reversed; slip:
the normal component reversed), pore pressure (impermeable: the total head of Eq. (25)
continued into the wall, p_j + rho_l b.(x_b - x_j); drained: -p~), effective stress,
porosity, density and conductivity. Two things are 3D-specific:

- the wall's shear is a vector, the tangential part tau = sigma'~ n - sigma'~_nn n of the
  traction: kept on a fixed wall, reversed on a slip wall (sigma'_b = sigma'~ - 2 (tau n^T
  + n tau^T)); on a friction wall the Coulomb limit holds for the pair sum of Eq. (26)
  itself, sum_j V_j (sigma'_j + sigma'_b) n dW_jb/dn over the soil particles j that b
  reaches: with the soil's traction averaged with those weights, |dW/dr| n.(x_j - x_b)/r
  (hat), where |tau^| exceeds tau_max = tan(phi_b) max(-sigma'^_nn,s, 0) the wall's shear
  is 2 tau_max tau^/|tau^| - tau^, so that the pairs carry tau_max along tau^. The normal
  stress sigma'^_nn,s is the one at the surface: the soil's, continued by the weight of
  the soil between it and the surface (and p to the surface's). With the Shepard
  averages (weights W) and the normal stress read above the surface, as in 2D, a block
  n = 2, 4, 8 rows thick sliding on the surface got 0.70, 0.78, 0.83 of its Coulomb
  friction (`bench/studies/floor_friction.py`);
- the wall-normal total stress is continued with the weight of the soil between j and b
  across the wall, min(-rho_j (b.n)(n.(x_b - x_j)), 0) (zero on a side wall, whose
  normal is horizontal), and the pore pressure difference p_b - p_j, as the plane ghosts
  do (`ghosts.py`, module docstring): a geostatic column then stays linear across the
  wall, where a plain average leaves its bottom row short of support. The polylines of
  2D do not add it (their bits are kept). The friction's normal stress is the soil's
  averaged one, before this continuation, as in 2D.

Boundary particles are fixed in space, below (or behind) the surface on the soil's
lattice. Unlike a mirror ghost, which coincides with a particle lying on the wall plane
and then gives it neither support nor friction, they stay where they are: a particle
that reaches the surface still has rows of them under it (docs/vv/collapse_3d.md).
"""

import math

import numba as nb

from psph.kernels.boundary import MOTION_FIXED, MOTION_FRICTION, MOTION_SLIP
from psph.kernels.spline import dw_cubic, w_cubic


@nb.njit(cache=True, inline="always")
def _cell_xyz(c, ncx, ncy):
    """(cx, cy, cz) of cell c, x fastest (`neighbours.bin_particles`)."""
    cx = c % ncx
    cyz = c // ncx
    return cx, cyz % ncy, cyz // ncy


@nb.njit(cache=True, inline="always")
def _add_sym(stress, b, a0, a1, a2, n0, n1, n2, f):
    """stress[b] += f (a n^T + n a^T) in Voigt order xx, yy, zz, xy, yz, zx."""
    stress[b, 0] += f * 2.0 * a0 * n0
    stress[b, 1] += f * 2.0 * a1 * n1
    stress[b, 2] += f * 2.0 * a2 * n2
    stress[b, 3] += f * (a0 * n1 + a1 * n0)
    stress[b, 4] += f * (a1 * n2 + a2 * n1)
    stress[b, 5] += f * (a2 * n0 + a0 * n2)


@nb.njit(cache=True, inline="always")
def _add_row(stress, j, f, a0, a1, a2, a3, a4, a5):
    """(a0, ..., a5) + f stress[j, :6]: a weighted sum's step over the six components."""
    return (a0 + f * stress[j, 0], a1 + f * stress[j, 1], a2 + f * stress[j, 2],
            a3 + f * stress[j, 3], a4 + f * stress[j, 4], a5 + f * stress[j, 5])


@nb.njit(cache=True)
def boundary_state_3d(n_real, rows, pts, f, head_b, body, cells, h):
    """State of the boundary rows (module docstring), and v copied into v_slip on the
    real rows. The 27 cells around a boundary particle are visited in a fixed order and a
    cell's particles in key order: the sums are the same on any number of ranks while
    every soil particle within 2h of it is a real row (a halo of 4h).

    Parameters
    ----------
    n_real : int
        real rows (owned and halo): the soil.
    rows : bundles.BoundaryRows
        the boundary rows first..first+n-1; row first + r holds the surface boundary
        particle src[r].
    pts : bundles.BoundaryPoints
        the surfaces' boundary particles: their surface's motion, tan_phi and drained,
        their unit normal into the soil and a point `foot` of their surface (m)
        (weight_dv, half_weight unused).
    f : bundles.WallFields
        every row's fields (3D); the boundary rows' velocity, v_slip (m/s), effective
        stress (Pa), p, p_prev (Pa), porosity, density (kg/m^3), conductivity (m/s) and
        acceleration (m/s^2) are written (vol and key unused).
    head_b : (3,) float array
        rho_l times the body force (N/m^3), for the hydrostatic pressure shift.
    body : (3,) float array
        the body force b (m/s^2), for the weight of the soil between a particle and the
        boundary particle.
    cells : bundles.CellList
        the step's cell lists of side 2h over every row.
    h : float
        smoothing length (m).
    """
    first, n_b, src = rows
    motion, tan_phi, drained, normal, foot = (pts.motion, pts.tan_phi, pts.drained,
                                              pts.normal, pts.foot)
    x, v, v_slip, stress, p, p_prev = f.x, f.v, f.v_slip, f.stress, f.p, f.p_prev
    poro, rho, perm, acc = f.poro, f.rho, f.perm, f.acc
    cell_of, cell_start, order, ncell = cells
    for j in range(n_real):
        for d in range(3):
            v_slip[j, d] = v[j, d]
    ncx, ncy, ncz = ncell[0], ncell[1], ncell[2]
    support2 = 4.0 * h * h
    for r in range(n_b):
        b = first + r
        k = src[r]
        cx, cy, cz = _cell_xyz(cell_of[b], ncx, ncy)
        n0, n1, n2 = normal[k, 0], normal[k, 1], normal[k, 2]
        bn = body[0] * n0 + body[1] * n1 + body[2] * n2
        ws = sv0 = sv1 = sv2 = sa0 = sa1 = sa2 = 0.0
        sp = spp = snn = 0.0
        s0 = s1 = s2 = s3 = s4 = s5 = 0.0
        sn = sr = sk = 0.0
        friction = motion[k] == MOTION_FRICTION
        f0, f1, f2 = foot[k, 0], foot[k, 1], foot[k, 2]
        s_surface = 0.0  # the normal stress's continuation to the surface (friction)
        # friction: the soil's stress weighted as the pair sum of Eq. (26) weights it,
        # by the normal component of the kernel gradient (module docstring)
        gs = g0 = g1 = g2 = g3 = g4 = g5 = 0.0
        for oz in range(-1, 2):
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
                        j = order[s]
                        if j >= n_real:
                            continue
                        d0 = x[b, 0] - x[j, 0]
                        d1 = x[b, 1] - x[j, 1]
                        d2 = x[b, 2] - x[j, 2]
                        r2 = d0 * d0 + d1 * d1 + d2 * d2
                        if r2 >= support2:
                            continue
                        w = w_cubic(math.sqrt(r2), h)
                        ws += w
                        sv0 += w * v[j, 0]
                        sv1 += w * v[j, 1]
                        sv2 += w * v[j, 2]
                        sa0 += w * acc[j, 0]
                        sa1 += w * acc[j, 1]
                        sa2 += w * acc[j, 2]
                        if drained[k]:
                            dp = -2.0 * p[j]
                            spp -= w * p_prev[j]
                        else:
                            dp = head_b[0] * d0 + head_b[1] * d1 + head_b[2] * d2
                            spp += w * (p_prev[j] + dp)
                        sp += w * (p[j] + dp)
                        # the weight of the soil between j and b across the wall: the
                        # normal components only, as the ghosts' (zero on a side wall)
                        weight = min(-rho[j] * bn * (n0 * d0 + n1 * d1 + n2 * d2), 0.0)
                        snn += w * (weight + dp)
                        if friction:
                            r = math.sqrt(r2)
                            gn = 0.0
                            if r > 0.0:
                                gn = -dw_cubic(r, h) * (n0 * d0 + n1 * d1 + n2 * d2) / r
                                gn = max(-gn, 0.0)
                                gs += gn
                                g0, g1, g2, g3, g4, g5 = _add_row(stress, j, gn, g0, g1, g2,
                                                                  g3, g4, g5)
                            e0 = f0 - x[j, 0]
                            e1 = f1 - x[j, 1]
                            e2 = f2 - x[j, 2]
                            ws_ = min(-rho[j] * bn * (n0 * e0 + n1 * e1 + n2 * e2), 0.0)
                            if drained[k]:
                                s_surface += gn * (ws_ - p[j])
                            else:
                                s_surface += gn * (ws_ + head_b[0] * e0 + head_b[1] * e1
                                                   + head_b[2] * e2)
                        s0, s1, s2, s3, s4, s5 = _add_row(stress, j, w, s0, s1, s2, s3, s4,
                                                          s5)
                        sn += w * poro[j]
                        sr += w * rho[j]
                        sk += w * perm[j]
        if ws == 0.0:
            for d in range(3):
                v[b, d] = v_slip[b, d] = acc[b, d] = 0.0
            for q in range(6):
                stress[b, q] = 0.0
            p[b] = p_prev[b] = 0.0
            poro[b] = 0.5
            rho[b] = 1.0
            perm[b] = 0.0
            continue
        iw = 1.0 / ws
        stress[b, 0] = s0 * iw
        stress[b, 1] = s1 * iw
        stress[b, 2] = s2 * iw
        stress[b, 3] = s3 * iw
        stress[b, 4] = s4 * iw
        stress[b, 5] = s5 * iw
        # the traction of the soil's averaged stress on the wall: the friction's normal
        # stress (as in 2D), and the shear that slip and friction change
        t0 = stress[b, 0] * n0 + stress[b, 3] * n1 + stress[b, 5] * n2
        t1 = stress[b, 3] * n0 + stress[b, 1] * n1 + stress[b, 4] * n2
        t2 = stress[b, 5] * n0 + stress[b, 4] * n1 + stress[b, 2] * n2
        s_nn = t0 * n0 + t1 * n1 + t2 * n2
        tau0 = t0 - s_nn * n0
        tau1 = t1 - s_nn * n1
        tau2 = t2 - s_nn * n2
        mode = motion[k]
        if mode == MOTION_FRICTION and gs == 0.0:
            # no soil particle toward the wall's side of b (at a surface's edge): the
            # Shepard averages' limit
            cap = tan_phi[k] * max(-s_nn, 0.0)
            tau = math.sqrt(tau0 * tau0 + tau1 * tau1 + tau2 * tau2)
            if tau <= cap:
                mode = MOTION_FIXED
            else:
                _add_sym(stress, b, tau0, tau1, tau2, n0, n1, n2, 2.0 * cap / tau - 2.0)
        elif mode == MOTION_FRICTION:
            # the Coulomb limit on the pair sum of Eq. (26) over the soil particles j
            # that b reaches, sum_j (sigma_j + sigma_b) n dW_jb/dn: the soil's traction
            # averaged with those weights (hat), its normal stress continued to the
            # surface by the weight of the soil between (the averaged normal stress read
            # above the surface, and the shear weighted by W, gave a block n rows thick
            # 0.70-0.83 of its Coulomb friction)
            ig = 1.0 / gs
            h0 = (g0 * n0 + g3 * n1 + g5 * n2) * ig
            h1 = (g3 * n0 + g1 * n1 + g4 * n2) * ig
            h2 = (g5 * n0 + g4 * n1 + g2 * n2) * ig
            h_nn = h0 * n0 + h1 * n1 + h2 * n2
            th0 = h0 - h_nn * n0
            th1 = h1 - h_nn * n1
            th2 = h2 - h_nn * n2
            cap = tan_phi[k] * max(-(h_nn + s_surface * ig), 0.0)
            tau = math.sqrt(th0 * th0 + th1 * th1 + th2 * th2)
            if tau <= cap:
                mode = MOTION_FIXED
            else:  # the wall's shear 2 cap tau_hat / |tau_hat| - tau_hat
                _add_sym(stress, b, tau0, tau1, tau2, n0, n1, n2, -1.0)
                _add_sym(stress, b, th0, th1, th2, n0, n1, n2, 2.0 * cap / tau - 1.0)
        elif mode == MOTION_SLIP:
            _add_sym(stress, b, tau0, tau1, tau2, n0, n1, n2, -2.0)
        # the normal stress continued across the wall (module docstring): += dnn n n^T,
        # which leaves the tangential traction as it is
        _add_sym(stress, b, n0, n1, n2, n0, n1, n2, 0.5 * snn * iw)
        vt0, vt1, vt2 = sv0 * iw, sv1 * iw, sv2 * iw
        at0, at1, at2 = sa0 * iw, sa1 * iw, sa2 * iw
        vn = vt0 * n0 + vt1 * n1 + vt2 * n2
        an = at0 * n0 + at1 * n1 + at2 * n2
        v_slip[b, 0] = vt0 - 2.0 * vn * n0
        v_slip[b, 1] = vt1 - 2.0 * vn * n1
        v_slip[b, 2] = vt2 - 2.0 * vn * n2
        if mode == MOTION_FIXED:
            v[b, 0], v[b, 1], v[b, 2] = -vt0, -vt1, -vt2
            acc[b, 0], acc[b, 1], acc[b, 2] = -at0, -at1, -at2
        else:
            v[b, 0], v[b, 1], v[b, 2] = v_slip[b, 0], v_slip[b, 1], v_slip[b, 2]
            acc[b, 0] = at0 - 2.0 * an * n0
            acc[b, 1] = at1 - 2.0 * an * n1
            acc[b, 2] = at2 - 2.0 * an * n2
        p[b] = sp * iw
        p_prev[b] = spp * iw
        poro[b] = sn * iw
        rho[b] = sr * iw
        perm[b] = sk * iw

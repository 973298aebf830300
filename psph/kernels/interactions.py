"""The fused pair loop: every neighbour sum of one coupled step in one sweep.

Each pair (a, b) with |x_a - x_b| < 2h is visited once (half stencil over the cell list)
and contributes to both particles. The corrected gradient, Eq. (22) of Lian et al. (2023),
needs the inverse of the moment matrix M_i = sum_j V_j (x_j - x_i) (x) grad_i W_ij, which is
only known after the sweep; since the correction is linear, the sweep accumulates raw sums
and `update.py` applies M_i^-1 afterwards. The columns of `sums` (one row per particle) are
named in `sum_columns.py`: the moment matrix M, the velocity, pressure and porosity-rate
gradients GV, GP, GN (Eq. 22, 24), the Darcy sums Q, SUM_A, SUM_AP, SUM_APSI (Eq. 23, 33,
38), the div(k dv/dt) sums GA, the stress divergence DVDT (Eq. 26) and the wall stretching
correction GS. Only rows of owned particles (index < n_owned) are written.

Walls. Rows n_real.. are wall ghosts. On them `v_slip` (vs) holds the velocity mirrored as
on a free-slip wall, where `v` holds -v on a fixed (no-slip) wall. GN takes vs, and
GV + GS is the velocity gradient with vs; only pairs with a ghost add to GS.
`update.advance` takes div v (Eq. 24-25) and the normal strain rates from GV + GS, the
shear rate from GV. Why: mirror ghosts exist only under the soil, so the no-slip ghost
layer under soil sliding at U ends where the soil ends, and at a debris front a particle
would "stretch" against its own ghosts by about 0.4 U/dx of spurious div v
(tests/test_walls.py), which Eq. (24)-(25) turn into run-away suction. A fixed wall
resists shear, not stretching along itself; the paper's virtual wall particles [11] line
the whole base and do not have this defect. On free-slip ghosts vs = v, so GS = 0 without
a fixed wall.

The artificial viscosity (Monaghan, in C_ij of Eq. 26) takes vs on ghost pairs: with -v,
the ghosts ahead of a particle sliding at U approach it at 2U, those behind recede, and the
one-sided term pushes the bottom row backward and upward, a numerical drag (7x the soil's
strength) and lift (suction under a nearly undrained soil). In a dry scene it acts between
real particles only, not on pairs with a ghost or boundary particle (rows n_real..): even
with vs a ghost pair keeps a wall-normal dashpot (a particle approaching the wall at v_n
approaches its mirror at 2 v_n and is pushed back with a stress of about
rho alpha c h v_n / y, y its distance from the wall) that is not the soil's. A soil that
thins toward the wall as it flows (a layer stretched along the floor, isochoric at
psi = 0) would rest on that dashpot instead of on its own sigma_nn, relax its sigma_nn and
its Drucker-Prager strength with it, and slide at about half of g sin(theta). The wall's
reactions are the ghosts' stresses: the normal one with the weight continued
(`ghosts.py`), the shear one on a fixed wall, which resists sliding. A coupled scene keeps
the ghost pairs' viscosity: without it the saturated sliding block of
tests/test_basal_sliding.py reaches -112 kPa of excess p at its base (-67 kPa with it).
"""

import math

import numba as nb

from psph.kernels.dims import add_moment, add_outer, mirror_moment, pick, velocity_differences
from psph.kernels.neighbours import forward_slots, half_stencil_rows, next_cell, pair_cell_span
from psph.kernels.spline import dw_cubic_dim, w_cubic_dim
from psph.kernels.sum_columns import sum_layout


def fastmath_of(dim: int):
    """LLVM's fast-math flags of the 3D sweep: a division by a pair's r or rho may become a
    product with its reciprocal ("arcp") and a product and a sum one fused multiply-add
    ("contract"): 1.2x on the 3D sweep, the same bits on any partition (each pair's
    arithmetic is the same code on every rank). The fused operations are the CPU's and
    LLVM's choice, so 3D bits are those of one machine type and one numba version: a
    restart on another kind of node continues the run, not its bits. None in 2D, which
    keeps its bits on any machine.

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    set of str or False
        numba's `fastmath` argument.
    """
    return {"arcp", "contract"} if dim == 3 else False


def make_pair_sums(dim: int):
    """`pair_sums` in `dim` = 2 or 3 dimensions (one source, `dims.py`), stress in Voigt
    order xx, yy, zz, xy (2D) and yz, zx (3D).

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `pair_sums`.
    """
    lay = sum_layout(dim)
    cm, cgv, cgp, cgn, cq = lay.M, lay.GV, lay.GP, lay.GN, lay.Q
    ca, cap_, capsi, cga, cdv, cgs = (lay.SUM_A, lay.SUM_AP, lay.SUM_APSI, lay.GA,
                                      lay.DVDT, lay.GS)
    nsums = lay.NSUMS
    span = pair_cell_span(dim)  # the grid of `cells` has cells of side 2h / span
    n_rows = half_stencil_rows(dim, span)
    as_xy = 2 if dim == 2 else 3  # the artificial stress's xy column

    @nb.njit(cache=True, error_model="numpy", fastmath=fastmath_of(dim))
    def pair_sums(n_total, n_owned, n_real, f, cells, par, sums, rec):
        """Accumulate the sums of `sum_columns.py` (`sum_layout(dim)`) for particles
        0..n_owned-1.

        Parameters
        ----------
        n_total : int
            rows in use: owned, halo, then wall ghosts.
        n_owned : int
            owned rows 0..n_owned-1.
        n_real : int
            rows n_real.. are wall ghosts, whose `v_slip` (free-slip mirror) enters GN and
            GS (module docstring).
        f : `bundles.PairFields`
            the fields of rows 0..n_total-1 (SI units: m, m/s, Pa, m^3, kg/m^3, m/s for
            the hydraulic conductivity, m/s^2); the artificial stress f.astress (Pa; xx,
            yy, xy; 3D: xx, yy, zz, xy, yz, zx) enters the pair stress with weight
            (W(r) / w_dx)^as_n (C_ij of Eq. 26).
        cells : `bundles.Cells`
            the pair sweep's grid (cells of side 2h / `neighbours.pair_cell_span(dim)`:
            side h in 3D).
        par : `bundles.PairParams`
            h (m); coupled: compute the pressure-related sums (GP, GN, Q, SUM_A, SUM_AP,
            SUM_APSI); acc_term: the div(k dv/dt) sums GA; rho_l_b = rho_l times the body
            force (N/m^3); as_n = 0: no artificial stress; p_weight = 1 puts the pore
            pressure in the pair's total stress (Eq. 26 as written), 0 leaves it out for
            `update.pore_pressure_force` to add it as a corrected gradient; record: write
            the visited pairs.
        sums : (cap, nsums) float64 array
            receives the sums of the owned rows.
        rec : `bundles.PairRecord`
            receives the visited pairs (a, b) and grad_a W_ab (1/m^(dim+1)) in visiting
            order when par.record, for `velocity_gradient_sums`.

        Returns
        -------
        int
            the number of pairs recorded, or minus the number of pairs if rec.pairs is too
            short for them (the sums are complete either way).
        """
        v, v_slip, stress, p, p_prev = f.v, f.v_slip, f.stress, f.p, f.p_prev
        poro, vol, rho, perm, acc, astress = f.poro, f.vol, f.rho, f.perm, f.acc, f.astress
        cell_start, order, ncell = cells.cell_start, cells.order, cells.ncell
        xs, owned_before = cells.x_sorted, cells.owned_before
        h, tpi_alpha, av_alpha, av_beta = par.h, par.tpi_alpha, par.av_alpha, par.av_beta
        c_sound, rho_l_b0, rho_l_b1 = par.c_sound, par.rho_l_b0, par.rho_l_b1
        rho_l_b2 = par.rho_l_b2
        coupled, acc_term, as_n, w_dx = par.coupled, par.acc_term, par.as_n, par.w_dx
        p_weight, record = par.p_weight, par.record
        pairs, pair_g = rec.pairs, rec.pair_g
        n_pairs = 0
        cap_pairs = pairs.shape[0]
        for i in range(n_owned):
            for c in range(nsums):
                sums[i, c] = 0.0
        ncx = ncell[0]
        ncy = ncell[1]
        ncz = ncell[2] if dim == 3 else 1
        support2 = 4.0 * h * h
        eps2 = 0.01 * h * h
        cx, cy, cz = -1, 0, 0
        for c in range(ncx * ncy * ncz):  # row-major, x fastest: the global cell order
            cx, cy, cz = next_cell(cx, cy, cz, ncx, ncy)
            for sa in range(cell_start[c], cell_start[c + 1]):
                a = order[sa]
                own_a = a < n_owned
                ghost_a = a >= n_real
                # a's fields, loaded once for all its pairs (the same values, so the same
                # bits, as loading them in every pair)
                xa0 = xs[sa, 0]
                xa1 = xs[sa, 1]
                xa2 = xs[sa, 2] if dim == 3 else 0.0
                va0 = v[a, 0]
                va1 = v[a, 1]
                va2 = v[a, 2] if dim == 3 else 0.0
                sa0 = stress[a, 0]
                sa1 = stress[a, 1]
                sa2 = stress[a, 2] if dim == 3 else 0.0
                sa3 = stress[a, 3]
                sa4 = stress[a, 4] if dim == 3 else 0.0
                sa5 = stress[a, 5] if dim == 3 else 0.0
                p_a = p[a]
                va = vol[a]
                rho_a = rho[a]
                poro_a = poro[a]
                perm_a = perm[a]
                pta = p_a + tpi_alpha * (p_a - p_prev[a]) if coupled else 0.0
                kaa0 = kaa1 = kaa2 = 0.0
                if acc_term and coupled:
                    kaa0 = perm_a * acc[a, 0]
                    kaa1 = perm_a * acc[a, 1]
                    kaa2 = perm_a * acc[a, 2] if dim == 3 else 0.0
                for row in range(n_rows):
                    s0, s1 = forward_slots(row, c, sa, cx, cy, cz, ncx, ncy, ncz, cell_start,
                                           dim, span)
                    # a halo or ghost row pairs only with owned ones: skip runs without
                    if not own_a and owned_before[s1] == owned_before[s0]:
                        continue
                    for sb in range(s0, s1):
                        b = order[sb]
                        own_b = b < n_owned
                        if not (own_a or own_b):
                            continue
                        dx0 = xs[sb, 0] - xa0
                        dx1 = xs[sb, 1] - xa1
                        dx2 = xs[sb, 2] - xa2 if dim == 3 else 0.0
                        r2 = dx0 * dx0 + dx1 * dx1
                        if dim == 3:
                            r2 += dx2 * dx2
                        if r2 >= support2 or r2 == 0.0:
                            continue
                        r = math.sqrt(r2)
                        dw = dw_cubic_dim(r, h, dim)
                        g0 = -dw * dx0 / r  # grad_a W_ab; grad_b W_ba = -g
                        g1 = -dw * dx1 / r
                        g2 = -dw * dx2 / r if dim == 3 else 0.0
                        f2 = -2.0 * dw / r  # 2 F_ab >= 0
                        if record:
                            if n_pairs < cap_pairs:
                                pairs[n_pairs, 0] = a
                                pairs[n_pairs, 1] = b
                                pair_g[n_pairs, 0] = g0
                                pair_g[n_pairs, 1] = g1
                                if dim == 3:
                                    pair_g[n_pairs, 2] = g2
                            n_pairs += 1
                        vb = vol[b]
                        ghost_pair = ghost_a or b >= n_real
                        dv0, dv1, dv2, ds0, ds1, ds2 = velocity_differences(
                            v, v_slip, a, b, va0, va1, va2, ghost_pair, dim)
                        # total stress sum sigma_a + sigma_b (Eq. 2: sigma = sigma' - p I)
                        p_b = p[b]
                        pab = p_weight * (p_a + p_b)
                        sxx = sa0 + stress[b, 0] - pab
                        syy = sa1 + stress[b, 1] - pab
                        sxy = sa3 + stress[b, 3]
                        szz = sa2 + stress[b, 2] - pab if dim == 3 else 0.0
                        syz = sa4 + stress[b, 4] if dim == 3 else 0.0
                        szx = sa5 + stress[b, 5] if dim == 3 else 0.0
                        if as_n > 0.0:
                            fn = (w_cubic_dim(r, h, dim) / w_dx) ** as_n
                            sxx += fn * (astress[a, 0] + astress[b, 0])
                            syy += fn * (astress[a, 1] + astress[b, 1])
                            sxy += fn * (astress[a, as_xy] + astress[b, as_xy])
                            if dim == 3:
                                szz += fn * (astress[a, 2] + astress[b, 2])
                                syz += fn * (astress[a, 4] + astress[b, 4])
                                szx += fn * (astress[a, 5] + astress[b, 5])
                        t0 = sxx * g0 + sxy * g1
                        t1 = sxy * g0 + syy * g1
                        t2 = 0.0
                        if dim == 3:
                            t0 += szx * g2
                            t1 += syz * g2
                            t2 = szx * g0 + syz * g1 + szz * g2
                        rho_b = rho[b]
                        # artificial viscosity (Monaghan), part of C_ij in Eq. (26),
                        # between real particles only in a dry scene (the module
                        # docstring)
                        pi_ab = 0.0
                        vdotr = ds0 * dx0 + ds1 * dx1
                        if dim == 3:
                            vdotr += ds2 * dx2
                        if vdotr < 0.0 and (coupled or not ghost_pair):
                            mu = h * vdotr / (r2 + eps2)
                            pi_ab = (-av_alpha * c_sound * mu + av_beta * mu * mu) / (
                                0.5 * (rho_a + rho_b))
                        dp = kbar = ptb = dpsi = 0.0
                        if coupled:
                            dp = p_b - p_a
                            kbar = 0.5 * (perm_a + perm[b])
                            ptb = p_b + tpi_alpha * (p_b - p_prev[b])
                            head = rho_l_b0 * dx0 + rho_l_b1 * dx1
                            if dim == 3:
                                head += rho_l_b2 * dx2
                            dpsi = -head
                        ka0 = ka1 = ka2 = 0.0
                        if acc_term and coupled:
                            ka0 = perm[b] * acc[b, 0] - kaa0
                            ka1 = perm[b] * acc[b, 1] - kaa1
                            ka2 = perm[b] * acc[b, 2] - kaa2 if dim == 3 else 0.0
                        # every load before the first store into sums (which may alias
                        # them and would force reloads: dims.py)
                        visc_a = rho_b * vb * pi_ab
                        visc_b = rho_a * va * pi_ab
                        poro_b = poro[b]
                        dd0 = ds0 - dv0
                        dd1 = ds1 - dv1
                        dd2 = ds2 - dv2
                        # a's sums with V_b, then b's with V_a (x_ab and g change sign)
                        if own_a:
                            add_moment(sums, a, cm, dim, vb, dx0, dx1, dx2, g0, g1, g2)
                            add_outer(sums, a, cgv, dim, vb, dv0, dv1, dv2, g0, g1, g2)
                            if ghost_pair:
                                add_outer(sums, a, cgs, dim, vb, dd0, dd1, dd2, g0, g1, g2)
                            for m in range(dim):
                                sums[a, cdv + m] += (vb * pick(m, t0, t1, t2) / rho_a
                                                     - visc_a * pick(m, g0, g1, g2))
                            if coupled:
                                add_outer(sums, a, cgn, dim, vb * (1.0 - poro_b), ds0, ds1,
                                          ds2, g0, g1, g2)
                                for m in range(dim):
                                    gm = pick(m, g0, g1, g2)
                                    sums[a, cgp + m] += vb * dp * gm
                                    sums[a, cq + m] += vb * pick(m, dx0, dx1, dx2) * f2
                                aij = vb * kbar * f2
                                sums[a, ca] += aij
                                sums[a, cap_] += aij * ptb
                                sums[a, capsi] += aij * dpsi
                        if own_b:
                            add_moment(sums, b, cm, dim, va, dx0, dx1, dx2, g0, g1, g2)
                            add_outer(sums, b, cgv, dim, va, dv0, dv1, dv2, g0, g1, g2)
                            if ghost_pair:
                                add_outer(sums, b, cgs, dim, va, dd0, dd1, dd2, g0, g1, g2)
                            for m in range(dim):
                                sums[b, cdv + m] += (-va * pick(m, t0, t1, t2) / rho_b
                                                     + visc_b * pick(m, g0, g1, g2))
                            if coupled:
                                add_outer(sums, b, cgn, dim, va * (1.0 - poro_a), ds0, ds1,
                                          ds2, g0, g1, g2)
                                for m in range(dim):
                                    gm = pick(m, g0, g1, g2)
                                    sums[b, cgp + m] += va * dp * gm
                                    sums[b, cq + m] -= va * pick(m, dx0, dx1, dx2) * f2
                                aij = va * kbar * f2
                                sums[b, ca] += aij
                                sums[b, cap_] += aij * pta
                                sums[b, capsi] -= aij * dpsi
                        if acc_term and coupled:
                            if own_a:
                                add_outer(sums, a, cga, dim, vb, ka0, ka1, ka2, g0, g1, g2)
                            if own_b:
                                add_outer(sums, b, cga, dim, va, ka0, ka1, ka2, g0, g1, g2)
        if dim == 3:
            mirror_moment(sums, n_owned, cm)
        return n_pairs if n_pairs <= cap_pairs else -n_pairs

    return pair_sums


pair_sums = make_pair_sums(2)
pair_sums_3d = make_pair_sums(3)


def make_velocity_gradient_sums(dim: int):
    """`velocity_gradient_sums` in `dim` = 2 or 3 dimensions (one source, `dims.py`), over
    `sums` of `sum_layout(dim)`.

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `velocity_gradient_sums`.
    """
    lay = sum_layout(dim)
    gv, gs, gn, nt = lay.GV, lay.GS, lay.GN, dim * dim

    @nb.njit(cache=True, error_model="numpy")
    def velocity_gradient_sums(n_owned, n_real, n_pairs, pairs, pair_g, v, v_slip, poro, vol,
                               coupled, sums):
        """Recompute only the velocity sums GV, GS and, if `coupled`,
        GN of owned particles from the current `v` and `v_slip` (rows n_real..:
        wall ghosts), over the pairs `pair_sums` recorded (same positions, same order, so
        the sums are as partition-independent as pair_sums').

        Used by the symplectic step (`time.integrator = "symplectic"`): after the kick
        v^(n+1) = v^n + dt a^n, the stress (Eq. 11), porosity (Eq. 24) and pressure
        (Eq. 25) rates take the new velocity, the staggered order of the leapfrog
        Eq. (27). And by the pressure projection after its velocity correction.

        Parameters
        ----------
        n_owned : int
            owned rows 0..n_owned-1.
        n_real : int
            rows n_real.. are wall ghosts.
        n_pairs : int
            number of recorded pairs.
        pairs : (>= n_pairs, 2) int64 array
            the pairs (a, b) of `pair_sums`.
        pair_g : (>= n_pairs, dim) float64 array
            grad_a W_ab (1/m^(dim+1)).
        v, v_slip : (cap, dim) float64 arrays
            velocity and its free-slip mirror on ghosts (m/s).
        poro : (cap,) float64 array
            porosity n.
        vol : (cap,) float64 array
            particle volumes (m^3; m^2 per unit thickness in 2D).
        coupled : bool
            recompute GN too.
        sums : (cap, nsums) float64 array
            the pair sums; GV, GS (and GN) of the owned rows are overwritten.
        """
        for i in range(n_owned):
            for c in range(nt):
                sums[i, gv + c] = 0.0
                sums[i, gs + c] = 0.0
                if coupled:
                    sums[i, gn + c] = 0.0
        for k in range(n_pairs):
            a = pairs[k, 0]
            b = pairs[k, 1]
            g0 = pair_g[k, 0]
            g1 = pair_g[k, 1]
            g2 = pair_g[k, 2] if dim == 3 else 0.0
            ghost_pair = a >= n_real or b >= n_real
            dv0, dv1, dv2, ds0, ds1, ds2 = velocity_differences(
                v, v_slip, a, b, v[a, 0], v[a, 1], v[a, 2] if dim == 3 else 0.0, ghost_pair,
                dim)
            for side in range(2):  # a's sums with V_b, then b's with V_a
                i = a if side == 0 else b
                j = b if side == 0 else a
                if i >= n_owned:
                    continue
                vj = vol[j]
                add_outer(sums, i, gv, dim, vj, dv0, dv1, dv2, g0, g1, g2)
                if ghost_pair:
                    add_outer(sums, i, gs, dim, vj, ds0 - dv0, ds1 - dv1, ds2 - dv2, g0, g1, g2)
                if coupled:
                    add_outer(sums, i, gn, dim, vj * (1.0 - poro[j]), ds0, ds1, ds2, g0, g1, g2)

    return velocity_gradient_sums


velocity_gradient_sums = make_velocity_gradient_sums(2)
velocity_gradient_sums_3d = make_velocity_gradient_sums(3)


@nb.njit(cache=True)
def symmetric_gradient_sums(n_owned, n_pairs, pairs, pair_g, vol, q, out):
    """out_i = sum_j V_j (q_i + q_j) grad_i W_ij of owned particles over the pairs
    `pair_sums` recorded, in their visiting order (partition-independent): the
    pair-symmetric gradient of Eq. (26) for a scalar q (the projection's pressure
    correction), and with q = 1/2 the concentration gradient of particle shifting; 2D or
    3D by pair_g.

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    n_pairs : int
        number of recorded pairs.
    pairs : (>= n_pairs, 2) int64 array
        the pairs (a, b) of `pair_sums`.
    pair_g : (>= n_pairs, dim) float64 array
        grad_a W_ab (1/m^(dim+1)).
    vol : (cap,) float64 array
        particle volumes (m^3; m^2 per unit thickness in 2D).
    q : (cap,) float64 array
        the scalar (any unit, e.g. Pa).
    out : (cap, dim) float64 array
        receives the gradient sums (unit of q per m).
    """
    dim = pair_g.shape[1]
    for i in range(n_owned):
        for d in range(dim):
            out[i, d] = 0.0
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        f = q[a] + q[b]
        if a < n_owned:
            for d in range(dim):
                out[a, d] += vol[b] * f * pair_g[k, d]
        if b < n_owned:
            for d in range(dim):
                out[b, d] -= vol[a] * f * pair_g[k, d]

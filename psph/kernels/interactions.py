"""The fused pair loop: every neighbour sum of one coupled step in one sweep.

Each pair (a, b) with |x_a - x_b| < 2h is visited once (half stencil over the cell list)
and contributes to both particles. The corrected gradient Eq. (22) needs the inverse of the
moment matrix M_i = sum_j V_j (x_j - x_i) (x) grad_i W_ij, which is only known after the
sweep; since the correction is linear, the sweep accumulates raw sums and `update.py`
applies M_i^-1 afterwards. Columns of `sums` (one row per particle):

  0-3   M[m, n]  = sum V_j r_ji^m  dW^n                     moment matrix, Eq. (22)
  4-7   Gv[a, n] = sum V_j (v_j - v_i)^a dW^n               velocity gradient, Eq. (22)
  8-9   Gp[n]    = sum V_j (p_j - p_i) dW^n                 pressure gradient, Eq. (22)
  10-13 Gn[a, n] = sum V_j (1 - n_j)(v_j - v_i)^a dW^n      porosity rate, Eq. (24)*
  14-15 Q[m]     = sum V_j r_ji^m 2F_ij                     correction moment, Eq. (23)
  16    sA       = sum A_ij,  A_ij = V_j kbar_ij 2F_ij      Eq. (33) (trace of D^mn is 2)
  17    sAp      = sum A_ij p~_j,  p~ = p + alpha (p - p_prev)   Eq. (38)-(39)
  18    sApsi    = sum A_ij (psi_j - psi_i),  psi = -rho_l b.x   elevation head, Eq. (25)
  19-22 Ga[a, n] = sum V_j (k_j a_j - k_i a_i)^a dW^n       div(k dv/dt), Eq. (25)/(36)
  23-24 dvdt     = sum V_j (sigma_i + sigma_j)/rho_i . dW - sum m_j Pi_ij dW  Eq. (26)
  25-28 Gs[a, n] = sum V_j (vs_j - vs_i - v_j + v_i)^a dW^n  stretching correction*

with dW = grad_i W_ij (Eq. 21), F_ij = r_ji . grad_i W_ij / |r_ji|^2 and sigma the total
stress sigma' - p I (Eq. 2). Only rows of owned particles (index < n_owned) are written.

* Rows n_real.. are wall ghosts. On them `v_slip` (vs) holds the velocity mirrored as on
a free-slip wall, where `v` holds -v on a fixed (no-slip) wall. Gn takes vs, and
Gv + Gs is the velocity gradient with vs; only pairs with a ghost add to Gs.
`update.advance` takes div v (Eq. 24-25) and the normal strain rates from Gv + Gs, the
shear rate from Gv.
Why: mirror ghosts exist only under the soil, so the no-slip ghost layer under soil
sliding at U ends where the soil ends. At a debris front the particle "stretches"
against its own ghosts by about 0.4 U/dx of spurious div v (tests/test_walls.py), which
Eq. (24)-(25) turn into run-away suction. A fixed wall resists shear, not stretching
along itself; the paper's virtual wall particles [11] line the whole base and do not
have this defect. On free-slip ghosts vs = v, so Gs = 0 without a fixed wall.
The artificial viscosity (Monaghan, in C_ij of Eq. 26) also takes vs on ghost pairs: with
-v, the ghosts ahead of a particle sliding at U approached it at 2U, those behind receded,
and the one-sided term pushed the bottom row backward and upward. That drag (7x the
soil's strength) and lift (suction under a nearly undrained soil) were numerical
(issue 13, cause 1: `python -m psph.app.sliding`). The wall's resistance to sliding
is its shear stress, which the fixed-wall ghosts keep.
"""

import math

import numba as nb

from psph.kernels.neighbours import half_stencil
from psph.kernels.spline import dw_cubic, w_cubic

NSUMS = 29


@nb.njit(cache=True, error_model="numpy")
def pair_sums(n_total, n_owned, n_real, x, v, v_slip, stress, p, p_prev, poro, vol, rho, perm, acc,
              cell_start, order, ncell, h, tpi_alpha, av_alpha, av_beta, c_sound,
              rho_l_b0, rho_l_b1, coupled, acc_term, sums, astress, as_n, w_dx,
              p_weight, record, pairs, pair_g):
    """Accumulate the sums listed in the module docstring for particles 0..n_owned-1.

    n_real: rows n_real..n_total-1 are wall ghosts, whose `v_slip` (free-slip mirror)
    enters Gn and Gs (see the module docstring).
    coupled: pressure-related sums (Gp, Gn, Q, sA, sAp, sApsi) are computed;
    acc_term: the div(k dv/dt) sums (Ga) are computed. rho_l_b = rho_l * body force (N/m^3).
    astress: (cap, 3) artificial stress R (xx, yy, xy) of every row, added to the pair
    stress with weight (W(r) / w_dx)^as_n (C_ij of Eq. 26); as_n = 0 switches it off.
    p_weight: 1 puts the pore pressure in the pair's total stress (Eq. 26 as written); 0
    leaves it out, for `update.pore_pressure_force` to add it as a corrected gradient.
    record: the visited pairs (a, b) and grad_a W_ab are written to pairs / pair_g in
    visiting order, for `velocity_gradient_sums`. Returns the number of pairs recorded,
    or -1 if `pairs` is too short (the sums are complete either way).
    """
    n_pairs = 0
    cap_pairs = pairs.shape[0]
    for i in range(n_owned):
        for c in range(NSUMS):
            sums[i, c] = 0.0
    ncx = ncell[0]
    ncy = ncell[1]
    support2 = 4.0 * h * h
    eps2 = 0.01 * h * h
    for cy in range(ncy):
        for cx in range(ncx):
            c = cy * ncx + cx
            for sa in range(cell_start[c], cell_start[c + 1]):
                a = order[sa]
                for k in range(5):
                    nc, s0 = half_stencil(k, c, sa, cx, cy, ncx, ncy, cell_start)
                    if nc < 0:
                        continue
                    for sb in range(s0, cell_start[nc + 1]):
                        b = order[sb]
                        own_a = a < n_owned
                        own_b = b < n_owned
                        if not (own_a or own_b):
                            continue
                        dx0 = x[b, 0] - x[a, 0]
                        dx1 = x[b, 1] - x[a, 1]
                        r2 = dx0 * dx0 + dx1 * dx1
                        if r2 >= support2 or r2 == 0.0:
                            continue
                        r = math.sqrt(r2)
                        dw = dw_cubic(r, h)
                        g0 = -dw * dx0 / r  # grad_a W_ab; grad_b W_ba = -g
                        g1 = -dw * dx1 / r
                        f2 = -2.0 * dw / r  # 2 F_ab >= 0
                        if record:
                            if n_pairs < cap_pairs:
                                pairs[n_pairs, 0] = a
                                pairs[n_pairs, 1] = b
                                pair_g[n_pairs, 0] = g0
                                pair_g[n_pairs, 1] = g1
                            n_pairs += 1
                        va = vol[a]
                        vb = vol[b]
                        dv0 = v[b, 0] - v[a, 0]
                        dv1 = v[b, 1] - v[a, 1]
                        ghost_pair = a >= n_real or b >= n_real
                        ds0 = dv0
                        ds1 = dv1
                        if ghost_pair:
                            ds0 = v_slip[b, 0] - v_slip[a, 0]
                            ds1 = v_slip[b, 1] - v_slip[a, 1]
                        # total stress sum sigma_a + sigma_b (Eq. 2: sigma = sigma' - p I)
                        pab = p_weight * (p[a] + p[b])
                        sxx = stress[a, 0] + stress[b, 0] - pab
                        syy = stress[a, 1] + stress[b, 1] - pab
                        sxy = stress[a, 3] + stress[b, 3]
                        if as_n > 0.0:
                            fn = (w_cubic(r, h) / w_dx) ** as_n
                            sxx += fn * (astress[a, 0] + astress[b, 0])
                            syy += fn * (astress[a, 1] + astress[b, 1])
                            sxy += fn * (astress[a, 2] + astress[b, 2])
                        f0 = sxx * g0 + sxy * g1
                        f1 = sxy * g0 + syy * g1
                        # artificial viscosity (Monaghan), part of C_ij in Eq. (26), on the
                        # free-slip relative velocity: see "Walls" in the module docstring
                        pi_ab = 0.0
                        vdotr = ds0 * dx0 + ds1 * dx1
                        if vdotr < 0.0:
                            mu = h * vdotr / (r2 + eps2)
                            pi_ab = (-av_alpha * c_sound * mu + av_beta * mu * mu) / (
                                0.5 * (rho[a] + rho[b]))
                        if coupled:
                            dp = p[b] - p[a]
                            kbar = 0.5 * (perm[a] + perm[b])
                            pta = p[a] + tpi_alpha * (p[a] - p_prev[a])
                            ptb = p[b] + tpi_alpha * (p[b] - p_prev[b])
                            dpsi = -(rho_l_b0 * dx0 + rho_l_b1 * dx1)
                        if own_a:
                            s = sums[a]
                            s[0] += vb * dx0 * g0
                            s[1] += vb * dx0 * g1
                            s[2] += vb * dx1 * g0
                            s[3] += vb * dx1 * g1
                            s[4] += vb * dv0 * g0
                            s[5] += vb * dv0 * g1
                            s[6] += vb * dv1 * g0
                            s[7] += vb * dv1 * g1
                            if ghost_pair:
                                s[25] += vb * (ds0 - dv0) * g0
                                s[26] += vb * (ds0 - dv0) * g1
                                s[27] += vb * (ds1 - dv1) * g0
                                s[28] += vb * (ds1 - dv1) * g1
                            s[23] += vb * f0 / rho[a] - rho[b] * vb * pi_ab * g0
                            s[24] += vb * f1 / rho[a] - rho[b] * vb * pi_ab * g1
                            if coupled:
                                s[8] += vb * dp * g0
                                s[9] += vb * dp * g1
                                wn = vb * (1.0 - poro[b])
                                s[10] += wn * ds0 * g0
                                s[11] += wn * ds0 * g1
                                s[12] += wn * ds1 * g0
                                s[13] += wn * ds1 * g1
                                s[14] += vb * dx0 * f2
                                s[15] += vb * dx1 * f2
                                aab = vb * kbar * f2
                                s[16] += aab
                                s[17] += aab * ptb
                                s[18] += aab * dpsi
                        if own_b:
                            s = sums[b]
                            s[0] += va * dx0 * g0
                            s[1] += va * dx0 * g1
                            s[2] += va * dx1 * g0
                            s[3] += va * dx1 * g1
                            s[4] += va * dv0 * g0
                            s[5] += va * dv0 * g1
                            s[6] += va * dv1 * g0
                            s[7] += va * dv1 * g1
                            if ghost_pair:
                                s[25] += va * (ds0 - dv0) * g0
                                s[26] += va * (ds0 - dv0) * g1
                                s[27] += va * (ds1 - dv1) * g0
                                s[28] += va * (ds1 - dv1) * g1
                            s[23] += -va * f0 / rho[b] + rho[a] * va * pi_ab * g0
                            s[24] += -va * f1 / rho[b] + rho[a] * va * pi_ab * g1
                            if coupled:
                                s[8] += va * dp * g0
                                s[9] += va * dp * g1
                                wn = va * (1.0 - poro[a])
                                s[10] += wn * ds0 * g0
                                s[11] += wn * ds0 * g1
                                s[12] += wn * ds1 * g0
                                s[13] += wn * ds1 * g1
                                s[14] -= va * dx0 * f2
                                s[15] -= va * dx1 * f2
                                aba = va * kbar * f2
                                s[16] += aba
                                s[17] += aba * pta
                                s[18] -= aba * dpsi
                        if acc_term and coupled:
                            ka0 = perm[b] * acc[b, 0] - perm[a] * acc[a, 0]
                            ka1 = perm[b] * acc[b, 1] - perm[a] * acc[a, 1]
                            if own_a:
                                s = sums[a]
                                s[19] += vb * ka0 * g0
                                s[20] += vb * ka0 * g1
                                s[21] += vb * ka1 * g0
                                s[22] += vb * ka1 * g1
                            if own_b:
                                s = sums[b]
                                s[19] += va * ka0 * g0
                                s[20] += va * ka0 * g1
                                s[21] += va * ka1 * g0
                                s[22] += va * ka1 * g1
    return n_pairs if n_pairs <= cap_pairs else -1


@nb.njit(cache=True, error_model="numpy")
def velocity_gradient_sums(n_owned, n_real, n_pairs, pairs, pair_g, v, v_slip, poro, vol, coupled,
                           sums):
    """Recompute only the velocity sums Gv (columns 4-7), Gs (25-28) and, if `coupled`,
    Gn (10-13) of owned particles from the current `v` and `v_slip` (rows n_real..:
    wall ghosts), over the pairs `pair_sums` recorded (same positions, same order, so
    the sums are as partition-independent as pair_sums').

    Used by the symplectic step (`time.integrator = "symplectic"`): after the kick
    v^(n+1) = v^n + dt a^n, the stress (Eq. 11), porosity (Eq. 24) and pressure (Eq. 25)
    rates take the new velocity, the staggered order of the leapfrog Eq. (27). And by the
    pressure projection after its velocity correction (`Simulation._project`).
    """
    for i in range(n_owned):
        for c in range(4, 8):
            sums[i, c] = 0.0
        for c in range(25, 29):
            sums[i, c] = 0.0
        if coupled:
            for c in range(10, 14):
                sums[i, c] = 0.0
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        g0 = pair_g[k, 0]
        g1 = pair_g[k, 1]
        dv0 = v[b, 0] - v[a, 0]
        dv1 = v[b, 1] - v[a, 1]
        ghost_pair = a >= n_real or b >= n_real
        ds0 = dv0
        ds1 = dv1
        if ghost_pair:
            ds0 = v_slip[b, 0] - v_slip[a, 0]
            ds1 = v_slip[b, 1] - v_slip[a, 1]
        if a < n_owned:
            s = sums[a]
            vb = vol[b]
            s[4] += vb * dv0 * g0
            s[5] += vb * dv0 * g1
            s[6] += vb * dv1 * g0
            s[7] += vb * dv1 * g1
            if ghost_pair:
                s[25] += vb * (ds0 - dv0) * g0
                s[26] += vb * (ds0 - dv0) * g1
                s[27] += vb * (ds1 - dv1) * g0
                s[28] += vb * (ds1 - dv1) * g1
            if coupled:
                wn = vb * (1.0 - poro[b])
                s[10] += wn * ds0 * g0
                s[11] += wn * ds0 * g1
                s[12] += wn * ds1 * g0
                s[13] += wn * ds1 * g1
        if b < n_owned:
            s = sums[b]
            va = vol[a]
            s[4] += va * dv0 * g0
            s[5] += va * dv0 * g1
            s[6] += va * dv1 * g0
            s[7] += va * dv1 * g1
            if ghost_pair:
                s[25] += va * (ds0 - dv0) * g0
                s[26] += va * (ds0 - dv0) * g1
                s[27] += va * (ds1 - dv1) * g0
                s[28] += va * (ds1 - dv1) * g1
            if coupled:
                wn = va * (1.0 - poro[a])
                s[10] += wn * ds0 * g0
                s[11] += wn * ds0 * g1
                s[12] += wn * ds1 * g0
                s[13] += wn * ds1 * g1


@nb.njit(cache=True)
def symmetric_gradient_sums(n_owned, n_pairs, pairs, pair_g, vol, q, out):
    """out_i = sum_j V_j (q_i + q_j) grad_i W_ij of owned particles over the pairs
    `pair_sums` recorded, in their visiting order (partition-independent): the
    pair-symmetric gradient of Eq. (26) for a scalar q (the projection's pressure
    correction), and with q = 1/2 the concentration gradient of particle shifting."""
    for i in range(n_owned):
        out[i, 0] = 0.0
        out[i, 1] = 0.0
    for k in range(n_pairs):
        a = pairs[k, 0]
        b = pairs[k, 1]
        f = q[a] + q[b]
        if a < n_owned:
            out[a, 0] += vol[b] * f * pair_g[k, 0]
            out[a, 1] += vol[b] * f * pair_g[k, 1]
        if b < n_owned:
            out[b, 0] -= vol[a] * f * pair_g[k, 0]
            out[b, 1] -= vol[a] * f * pair_g[k, 1]

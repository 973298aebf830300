"""Column layout of `sums`, the per-particle neighbour sums of one step's pair sweep
(`interactions.pair_sums`), one row per particle. Module-level integers: numba reads them
as compile-time constants, so `s[GV_XY]` costs what `s[5]` would.

With dW = grad_i W_ij (Eq. 21 of Lian et al. 2023), r_ji = x_j - x_i,
F_ij = r_ji . dW / |r_ji|^2, A_ij =
V_j kbar_ij 2F_ij (Eq. 33) and components m, n, a in (x, y):

  M_mn     sum V_j r_ji^m dW^n                        moment matrix, Eq. (22)
  GV_an    sum V_j (v_j - v_i)^a dW^n                 velocity gradient, Eq. (22)
  GP_n     sum V_j (p_j - p_i) dW^n                   pressure gradient, Eq. (22)
  GN_an    sum V_j (1 - n_j)(vs_j - vs_i)^a dW^n      porosity rate, Eq. (24)
  Q_m      sum V_j r_ji^m 2F_ij                       correction moment, Eq. (23)
  SUM_A    sum A_ij                                   Eq. (33) (trace of D^mn is 2)
  SUM_AP   sum A_ij p~_j, p~ = p + alpha (p - p_prev) Eq. (38)-(39)
  SUM_APSI sum A_ij (psi_j - psi_i), psi = -rho_l b.x elevation head, Eq. (25)
  GA_an    sum V_j (k_j a_j - k_i a_i)^a dW^n         div(k dv/dt), Eq. (25)/(36)
  DVDT_m   sum V_j (sigma_i + sigma_j)/rho_i . dW - sum m_j Pi_ij dW   Eq. (26)
  GS_an    sum V_j (vs_j - vs_i - v_j + v_i)^a dW^n   stretching correction at walls

vs is the free-slip mirror velocity on wall ghosts (`interactions.py`, "Walls"). The
two-index groups are row-major: XX, XY, YX, YY. The constants below are the 2D layout;
`sum_layout(dim)` gives the same groups in 2D or 3D.
"""

from typing import NamedTuple

M_XX, M_XY, M_YX, M_YY = 0, 1, 2, 3
GV_XX, GV_XY, GV_YX, GV_YY = 4, 5, 6, 7
GP_X, GP_Y = 8, 9
GN_XX, GN_XY, GN_YX, GN_YY = 10, 11, 12, 13
Q_X, Q_Y = 14, 15
SUM_A = 16
SUM_AP = 17
SUM_APSI = 18
GA_XX, GA_XY, GA_YX, GA_YY = 19, 20, 21, 22
DVDT_X, DVDT_Y = 23, 24
GS_XX, GS_XY, GS_YX, GS_YY = 25, 26, 27, 28
NSUMS = 29

# the Darcy sums (Q .. SUM_APSI) and the stress divergence, scaled by the lattice moment
# after the sweep (`Stages._interactions`)
DARCY = slice(Q_X, SUM_APSI + 1)
DVDT = slice(DVDT_X, DVDT_Y + 1)
MOMENT = slice(M_XX, M_YY + 1)
GV = slice(GV_XX, GV_YY + 1)
GN = slice(GN_XX, GN_YY + 1)
GS = slice(GS_XX, GS_YY + 1)
GP = slice(GP_X, GP_Y + 1)
Q = slice(Q_X, Q_Y + 1)


class SumLayout(NamedTuple):
    """First column of each group of `sums` in `dim` dimensions (tensor groups dim x dim,
    row-major; vector groups dim): kernels written once for 2D and 3D (`dims.py`) take
    their columns from `sum_layout(dim)`, a constant of each compiled specialisation."""
    dim: int
    M: int
    GV: int
    GP: int
    GN: int
    Q: int
    SUM_A: int
    SUM_AP: int
    SUM_APSI: int
    GA: int
    DVDT: int
    GS: int
    NSUMS: int


def sum_layout(dim: int) -> SumLayout:
    """The layout of `sums` in 2D (the module's constants above) or 3D: the same groups in
    the same order, each of its size in `dim` dimensions.

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    SumLayout
        the first column of each group and NSUMS.
    """
    t, v = dim * dim, dim
    sizes = (("M", t), ("GV", t), ("GP", v), ("GN", t), ("Q", v), ("SUM_A", 1),
             ("SUM_AP", 1), ("SUM_APSI", 1), ("GA", t), ("DVDT", v), ("GS", t))
    start, first = 0, {}
    for name, size in sizes:
        first[name] = start
        start += size
    return SumLayout(dim=dim, NSUMS=start, **first)

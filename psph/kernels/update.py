"""Per-particle update of one step from the sums of `interactions.pair_sums`.

Applies the correction matrix of Eq. (22) of Lian et al. (2023), then advances (leapfrog,
Eq. 27) the effective
stress (linear elastic, Jaumann rate, Eq. 11 without plasticity; plane strain), the
porosity (Eq. 24), the pore pressure (explicit Eq. 25 or TPI Eq. 38-39), the velocity
(Eq. 45: Eq. 26 + global damping Eq. 43-44 + body force + surface loads) and the position.
"""

import math

import numba as nb

from psph.kernels.bundles import DruckerPrager
from psph.kernels.free_surface import on_free_surface
from psph.kernels.kinematics import inverse_moment_3d, jaumann_elastic_3d, velocity_gradient_3d
from psph.kernels.plasticity import dp_return, dp_return_3d
from psph.kernels.sum_columns import (
    DVDT_X,
    DVDT_Y,
    GA_XX,
    GA_XY,
    GA_YX,
    GA_YY,
    GN_XX,
    GN_XY,
    GN_YX,
    GN_YY,
    GP_X,
    GP_Y,
    GS_XX,
    GS_XY,
    GS_YX,
    GS_YY,
    GV_XX,
    GV_XY,
    GV_YX,
    GV_YY,
    M_XX,
    M_XY,
    M_YX,
    M_YY,
    Q_X,
    Q_Y,
    SUM_APSI,
    sum_layout,
)

SCHEME_NONE = 0
SCHEME_EXPLICIT = 1
SCHEME_TPI = 2
SCHEME_PROJECTION = 3  # p^(n+1) solved before `advance` (psph/kernels/projection.py)

# columns of the material table (`psph.physics.material.material_table`): one row per
# material, indexed by a particle's `material` field
MAT_LAM = 0  # Lame lambda (Pa)
MAT_SHEAR = 1  # shear modulus mu (Pa)
MAT_BULK3 = 2  # 3K = 3 lambda + 2 mu (Pa)
MAT_RHO_S = 3  # grain density rho_s (kg/m^3)
MAT_K = 4  # hydraulic conductivity k_sat of Eq. (4) (m/s)
MAT_C_K = 5  # C_k of Eq. (4); 0: constant k
MAT_N_MIN = 6  # porosity floor of Eq. (24); 0: none
MAT_PLASTIC = 7  # 1: Drucker-Prager, 0: elastic
MAT_DP = 8  # 7 columns: phi_p, phi_r, c_p, c_r, psi_0, eta, s_f (Eq. 17-19, radians)
MAT_NL_LENGTH = MAT_DP + 7  # l_c of the non-local softening strain (m); 0: local
MAT_NL_M = MAT_DP + 8  # its over-non-local weight m (psph/kernels/nonlocal_strain.py)
MAT_TENSION = MAT_DP + 9  # tension cut-off of sigma'_m (Pa); inf: none (`dp_return`)
MAT_MOHR_COULOMB = MAT_DP + 10  # 1: the Lode-dependent Mohr-Coulomb cone (`dp_return_3d`)
MAT_COLUMNS = MAT_DP + 11


@nb.njit(cache=True, inline="always")
def _inverse_moment(s):
    """Inverse of the 2x2 moment matrix (row-major m00, m01, m10, m11); identity (no
    correction) where it is near-singular, e.g. a particle with too few neighbours."""
    det = s[M_XX] * s[M_YY] - s[M_XY] * s[M_YX]
    if abs(det) < 1e-3:
        return 1.0, 0.0, 0.0, 1.0
    inv = 1.0 / det
    return s[M_YY] * inv, -s[M_XY] * inv, -s[M_YX] * inv, s[M_XX] * inv


@nb.njit(cache=True, inline="always")
def drucker_prager(row):
    """The Drucker-Prager law of a material (`plasticity.dp_return_3d`) from its row of
    the material table.

    Parameters
    ----------
    row : (MAT_COLUMNS,) float64 array
        the material's row of the material table (`advance`).

    Returns
    -------
    `bundles.DruckerPrager`
        phi_p, phi_r (rad), c_p, c_r (Pa), psi_0 (rad), eta, s_f of Eq. (17)-(19), the
        tension cut-off (Pa) and the Mohr-Coulomb flag.
    """
    d = MAT_DP
    return DruckerPrager(row[d], row[d + 1], row[d + 2], row[d + 3], row[d + 4], row[d + 5],
                         row[d + 6], row[MAT_TENSION], row[MAT_MOHR_COULOMB] > 0.0)


@nb.njit(cache=True, inline="always")
def tpi_pressure(b_i, sum_a, sum_ap, p_i, beta, dt):
    """p_i^(t+1) of the TPI update: Eq. (38) with p~_j = p_j + alpha (p_j - p_j^prev) of
    Eq. (39) already summed in sum_ap = sum_j A_ij p~_j; with beta > 0, the storage of
    Eq. (47) where the pressure is negative, taken as the implicit step of

        beta (min(p^(t+1), 0) - min(p^t, 0)) / dt + (sum_j A_ij) p^(t+1) = B_i + sum_ap,

    a storage beta d min(p, 0) / dt. Its left side grows with p^(t+1), so the root is
    one: the numerator N = B_i + sum_ap + beta min(p^t, 0) / dt over sum_a (N >= 0) or
    over sum_a + beta / dt (N < 0). Where p^t < 0 and p^(t+1) < 0 this is Eq. (47) with
    p_i^t in its beta term; where both are >= 0, Eq. (38).

    Why not Eq. (47) as printed, which decides the branch by p^t and stores against
    p~_i^(t+alpha): beta / dt is thousands of times sum_a (5,600 at dx = 0.04, k = 2e-4,
    dt = 2e-5), so there a negative p barely moves; the step that crosses zero from above
    lands at Eq. (38)'s value, its one-sweep jump, which the storage then keeps, and the
    extrapolation carries every step's change on by alpha / (1 - alpha) again. The
    suction so held is set by the step: the saturated collapse at dt and dt / 2 differs
    by 1.7x in its most negative p after 1 ms and by 31 % in kinetic energy after 10 ms,
    where this form agrees to 2 % and 0.3 % (docs/vv/collapse_beta.md).

    Parameters
    ----------
    b_i : float
        B_i of Eq. (36) (Pa/(m s)).
    sum_a : float
        sum_j A_ij (Eq. 33), > 0 (1/(m s)).
    sum_ap : float
        sum_j A_ij p~_j (Pa/(m s)).
    p_i : float
        the particle's pressure p^t (Pa).
    beta : float
        the storage of Eq. (47) (1/m); 0: none.
    dt : float
        time step (s).

    Returns
    -------
    float
        p_i^(t+1) (Pa).
    """
    if beta > 0.0:
        num = b_i + sum_ap + beta * min(p_i, 0.0) / dt
        if num < 0.0:
            return num / (sum_a + beta / dt)
        return num / sum_a
    return (b_i + sum_ap) / sum_a


@nb.njit(cache=True, inline="always")
def _momentum(i, s, cdv, f, loads, b0, b1, b2, damping, dt, dim):
    """dv/dt of Eq. (45): Eq. (26) (the sums from column cdv) + body force + damping
    Eq. (43)-(44) + surface tractions (`bundles.SurfaceLoads`); stored in f.acc and
    applied to f.v (`bundles.UpdateFields`, dim components)."""
    v, acc, rho, vol = f.v, f.acc, f.rho, f.vol
    load_index, traction, load_value = loads.load_index, loads.traction, loads.load_value
    a0 = s[cdv] + b0 - damping * v[i, 0]
    a1 = s[cdv + 1] + b1 - damping * v[i, 1]
    a2 = s[cdv + 2] + b2 - damping * v[i, 2] if dim == 3 else 0.0
    li = int(load_index[i])
    if li >= 0:
        mass = rho[i] * vol[i]
        a0 += load_value[li] * traction[i, 0] / mass
        a1 += load_value[li] * traction[i, 1] / mass
        if dim == 3:
            a2 += load_value[li] * traction[i, 2] / mass
    acc[i, 0] = a0
    acc[i, 1] = a1
    v[i, 0] += dt * a0
    v[i, 1] += dt * a1
    if dim == 3:
        acc[i, 2] = a2
        v[i, 2] += dt * a2


@nb.njit(cache=True, inline="always")
def set_porosity(i, n_new, poro, poro0, vol, vol0, rho, perm, rho_s, rho_l, k_sat, c_k):
    """Porosity n_new for particle i and what follows from it: the volume with the solid
    mass kept (incompressible grains, Eq. 8), the mixture density and, where c_k > 0, the
    hydraulic conductivity from the void ratio, k = k_sat exp((e - e0) / c_k), Eq. (4).

    Parameters
    ----------
    i : int
        the particle's row.
    n_new : float
        the new porosity.
    poro, poro0 : (cap,) float64 arrays
        porosity and initial porosity; poro[i] is set.
    vol, vol0 : (cap,) float64 arrays
        volume and initial volume (m^3; m^2 in 2D); vol[i] is set.
    rho : (cap,) float64 array
        mixture density (kg/m^3); rho[i] is set.
    perm : (cap,) float64 array
        hydraulic conductivity k (m/s); perm[i] is set where c_k > 0.
    rho_s, rho_l : float
        grain and water densities (kg/m^3).
    k_sat : float
        hydraulic conductivity at the initial void ratio (m/s).
    c_k : float
        C_k of Eq. (4) (dimensionless); 0: constant k.
    """
    poro[i] = n_new
    vol[i] = vol0[i] * (1.0 - poro0[i]) / (1.0 - n_new)
    rho[i] = (1.0 - n_new) * rho_s + n_new * rho_l
    if c_k > 0.0:
        e0 = poro0[i] / (1.0 - poro0[i])
        perm[i] = k_sat * math.exp((n_new / (1.0 - n_new) - e0) / c_k)


@nb.njit(cache=True)
def porosity_follows_stress_filter(n_owned, trace_before, stress, f, rho_l, mat, material):
    """Move the porosity with the volumetric strain that the stress filter took out of (or
    put into) the effective stress, so that both keep carrying the same strain.

    The elastic update changes tr(sigma') by 3K div v per unit time (Eq. 11, plane strain)
    while Eq. (24) changes n by (1 - n) div v; a filter that replaces sigma' by its
    neighbours' fit (`mls_stress`, `shepard_stress`) changes tr(sigma') by d_tr without a
    strain, which Eq. (24) never sees. Left so, a particle whose div v is biased (a
    debris-front surface particle with 9-11 neighbours, p held at 0 by ponding) compacts in
    n while the filter keeps erasing the stress that would resist it (n 0.40 -> 0.021 in
    27 s of the retrogressive slope). Here n += (1 - n) d_tr / (3K), the elastic strain of
    d_tr.

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    trace_before : (cap,) float64 array
        tr(sigma') before the filter (Pa).
    stress : (cap, 4) or (cap, 6) float64 array
        the filtered effective stress (Pa).
    f : `bundles.PorosityFields`
        porosity, initial porosity, volume, initial volume (m^3; m^2 in 2D), mixture
        density (kg/m^3) and hydraulic conductivity (m/s), as `set_porosity`, updated.
    rho_l : float
        water density (kg/m^3).
    mat : (n_materials, MAT_COLUMNS) float64 array
        the material table (3K = 3 lambda + 2 mu, rho_s, k_sat, c_k in MAT_* columns).
    material : (cap,) float64 array
        each particle's row of `mat`.
    """
    for i in range(n_owned):
        row = mat[int(material[i])]
        d_tr = stress[i, 0] + stress[i, 1] + stress[i, 2] - trace_before[i]
        n_i = f.poro[i]
        set_porosity(i, n_i + (1.0 - n_i) * d_tr / row[MAT_BULK3], f.poro, f.poro0, f.vol,
                     f.vol0, f.rho, f.perm, row[MAT_RHO_S], rho_l, row[MAT_K], row[MAT_C_K])


@nb.njit(cache=True)
def porosity_follows_pressure_filter(n_owned, p_before, p, f, rho_l, mat, material, bulk_water):
    """Move the porosity with the volumetric strain that the pressure filter (Eq. 46) took
    out of (or put into) the pore pressure, so that p and n keep carrying the same strain.

    Undrained, Eq. (25) changes p by -(K_l / n) div v per unit time and Eq. (24) changes n
    by (1 - n) div v; the Shepard filter changes p by dp without a strain. Left so, a basal
    particle squeezed between two near-wall particles compacts in n (0.354 -> 0.304 in
    1 s) while the filter erases, every 30 steps, the pressure that resisted it. Here
    n += -(1 - n) n dp / K_l, the strain of dp. Off by default
    (`stabilisation.pressure_filter_porosity`): read as an exchange of pore water between
    neighbours, the filter moves no strain, and with the ponding clip this version
    compacts free-surface particles.

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    p_before : (cap,) float64 array
        p before the filter (Pa).
    p : (cap,) float64 array
        the filtered pore pressure (Pa).
    f : `bundles.PorosityFields`
        as `porosity_follows_stress_filter`, updated.
    rho_l : float
        water density (kg/m^3).
    mat, material
        the material table and each particle's row, as
        `porosity_follows_stress_filter`.
    bulk_water : float
        bulk modulus of water K_l (Pa).
    """
    for i in range(n_owned):
        row = mat[int(material[i])]
        n_i = f.poro[i]
        dp = p[i] - p_before[i]
        set_porosity(i, n_i - (1.0 - n_i) * n_i * dp / bulk_water, f.poro, f.poro0, f.vol,
                     f.vol0, f.rho, f.perm, row[MAT_RHO_S], rho_l, row[MAT_K], row[MAT_C_K])


@nb.njit(cache=True, error_model="numpy")
def pore_pressure_force(n_owned, sums, rho, corrected, norm, share):
    """The pore pressure's part of Eq. (26) as -grad p / rho_i from the pressure
    differences of sums 8-9, Gp = sum_j V_j (p_j - p_i) grad W_ij, added to dv/dt (sums
    23-24) of a sweep made with the pressure left out of the pair stress (`pair_sums`,
    p_weight = 0). corrected: grad p = Gp M^-1, Eq. (22), exact for a linear p on any
    arrangement; else grad p = norm Gp (norm = 1 / m0, the lattice moment).

    The pair-symmetric form -sum_j V_j (p_i + p_j) grad W_ij / rho_i holds the term
    -2 p_i S_i / rho_i, S_i = sum_j V_j grad W_ij, which vanishes only where the support
    is even: in a disordered basal layer a particle holds its place there with a
    pressure its neighbours do not have. Pressure differences exert no force from a
    uniform p on any arrangement (the wall ghosts carry the hydrostatic or the
    antisymmetric mirror of p), at the price of momentum conservation.

    Parameters
    ----------
    n_owned : int
        owned rows 0..n_owned-1.
    sums : (cap, nsums) float64 array
        the 2D pair sums; DVDT (m/s^2) is added to.
    rho : (cap,) float64 array
        mixture density (kg/m^3).
    corrected : bool
        use the corrected gradient of Eq. (22).
    norm : float
        1 / m0, the lattice moment (`laplacian.lattice_moment`).
    share : float
        the share of p in the force (1: all of it).
    """
    for i in range(n_owned):
        s = sums[i]
        if corrected:
            m00, m01, m10, m11 = _inverse_moment(s)
            s[DVDT_X] -= share * (s[GP_X] * m00 + s[GP_Y] * m10) / rho[i]
            s[DVDT_Y] -= share * (s[GP_X] * m01 + s[GP_Y] * m11) / rho[i]
        else:
            s[DVDT_X] -= share * norm * s[GP_X] / rho[i]
            s[DVDT_Y] -= share * norm * s[GP_Y] / rho[i]


def make_kick(dim: int):
    """`kick` in `dim` = 2 or 3 dimensions (one source, `dims.py`).

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `kick`.
    """
    cdv = sum_layout(dim).DVDT

    @nb.njit(cache=True, error_model="numpy")
    def kick(n_owned, sums, f, loads, b0, b1, damping, dt, b2=0.0):
        """The kick of the symplectic step, v^(n+1) = v^n + dt a^n (Eq. 45 at the state of
        step n); `advance(..., kicked=True)` then takes the rates from v^(n+1).

        Parameters
        ----------
        n_owned : int
            owned rows 0..n_owned-1.
        sums : (cap, nsums) float64 array
            the pair sums (DVDT: the acceleration of Eq. 26, m/s^2).
        f : `bundles.UpdateFields`
            the owned rows' fields: f.v, velocity (m/s), updated; f.acc receives the
            acceleration (m/s^2); f.rho, mixture density (kg/m^3); f.vol, particle
            volumes (m^3; m^2 per unit thickness in 2D).
        loads : `bundles.SurfaceLoads`
            each particle's surface load (load_index, -1: none) and tributary area vector
            -n dA (traction, m^2; m in 2D), and the loads' current values (load_value, Pa).
        b0, b1, b2 : float
            body force (m/s^2); b2 in 3D only.
        damping : float
            c_d of Eq. (44) (1/s).
        dt : float
            time step (s).
        """
        for i in range(n_owned):
            _momentum(i, sums[i], cdv, f, loads, b0, b1, b2, damping, dt, dim)

    return kick


kick = make_kick(2)
kick_3d = make_kick(3)


def make_advance(dim: int):
    """`advance` in `dim` = 2 or 3 dimensions (one source, `dims.py`); 2D is the
    plane-strain step.

    Parameters
    ----------
    dim : int
        2 or 3.

    Returns
    -------
    function
        the compiled `advance`.
    """
    lay = sum_layout(dim)
    cm, cgv, cgs, cgn, cgp, cq = lay.M, lay.GV, lay.GS, lay.GN, lay.GP, lay.Q
    ca, cap_, capsi, cga, cdv = lay.SUM_A, lay.SUM_AP, lay.SUM_APSI, lay.GA, lay.DVDT

    @nb.njit(cache=True, error_model="numpy")
    def advance(n_owned, sums, f, loads, mat, eps_soft, box, par):
        """Advance owned particles 0..n_owned-1 by dt. In 3D the same steps with the 3x3
        correction and the full spin (`kinematics.py`) and `plasticity.dp_return_3d`.

        The softening of phi and c, Eq. (17)-(18), takes eps_soft[i]; the decay of psi,
        Eq. (19), the particle's own eps_p: the approach to the critical state is the
        particle's own (with the regularised strain a row sliding on a wall, twice as
        strained as its support's average, would keep eps_hat = 0 and psi = psi_0 and
        contract to n = 0).

        Parameters
        ----------
        n_owned : int
            owned rows 0..n_owned-1.
        sums : (cap, nsums) float64 array
            the pair sums of `interactions.pair_sums`.
        f : `bundles.UpdateFields`
            the owned rows' fields (SI units), updated; p = 0 is imposed where
            f.drained_from <= t; f.eps_p accumulates the equivalent plastic strain and
            f.plastic_work the dissipated work sigma : d eps_p (J/m^3,
            `plasticity.dp_return`).
        loads : `bundles.SurfaceLoads`
            the surface loads (Pa) and each particle's tributary area vector.
        mat : (n_materials, MAT_COLUMNS) float64 array
            the material table, row int(material[i]) for particle i: Lame constants
            lambda, mu (Pa), rho_s (kg/m^3), k_sat (m/s) and c_k of Eq. (4), the porosity
            floor n_min (0: none), the Drucker-Prager flag and parameters (phi_p, phi_r,
            c_p, c_r, psi_0, eta, s_f of Eq. 13-19; rad, Pa), the tension cut-off (Pa) and
            the Mohr-Coulomb flag.
        eps_soft : (cap,) float64 array
            the strain that softens phi and c: eps_p itself (the local law) or the
            regularised strain of `nonlocal_strain.nonlocal_strain`.
        box : float64 array
            the domain (xmin, ymin[, zmin], xmax, ymax[, zmax]) (m).
        par : `bundles.StepParams`
            dt, t (s); bulk_water K_l (Pa); gamma_l = rho_l g (N/m^3) (one pore fluid);
            b0, b1[, b2]: body force (m/s^2); damping: c_d of Eq. (44) (1/s); scheme:
            0 dry, 1 explicit Eq. (25), 2 TPI Eq. (38) with the storage of Eq. (47) below
            zero when beta > 0 (`tpi_pressure`; alpha of Eq. 39 is in the sums),
            3 projection (p already solved); plastic: some material is Drucker-Prager;
            ponding: free-surface particles get p <= 0 (1, Section 4.4) or p = 0 (2);
            kicked: `kick` has already advanced v (symplectic step) and `sums` holds the
            velocity gradient of the new v, so only the position moves with it here.

        Returns
        -------
        int
            the index of the first particle with a non-finite pressure, velocity or
            stress, outside `box`, or (coupled) with a porosity outside (0, 1); -1 if none.
        """
        x, u, v, stress, p, p_prev = f.x, f.u, f.v, f.stress, f.p, f.p_prev
        poro, poro0, vol, vol0, rho, perm = f.poro, f.poro0, f.vol, f.vol0, f.rho, f.perm
        drained_from, material = f.drained_from, f.material
        eps_p, plastic_work = f.eps_p, f.plastic_work
        dt, t, bulk_water, gamma_l, rho_l = par.dt, par.t, par.bulk_water, par.gamma_l, par.rho_l
        b0, b1, damping, scheme, beta = par.b0, par.b1, par.damping, par.scheme, par.beta
        b2 = par.b2
        acc_term, correct_strain, plastic = par.acc_term, par.correct_strain, par.plastic
        ponding, kicked = par.ponding, par.kicked
        bad = -1
        inv_g = rho_l / gamma_l
        for i in range(n_owned):
            s = sums[i]
            row = mat[int(material[i])]
            lam = row[MAT_LAM]
            shear = row[MAT_SHEAR]
            if dim == 2:
                m00, m01, m10, m11 = _inverse_moment(s)
                # velocity gradient L[a, b] = dv_a/dx_b = G[a, n] Minv[n, b]   (Eq. 22): the
                # stretching (diagonal) from Gv + Gs, the shear from Gv (interactions.py: a fixed
                # wall resists shear, not stretching along itself)
                gs00 = s[GV_XX] + s[GS_XX]
                gs11 = s[GV_YY] + s[GS_YY]
                l00 = gs00 * m00 + (s[GV_XY] + s[GS_XY]) * m10
                l01 = s[GV_XX] * m01 + s[GV_XY] * m11
                l10 = s[GV_YX] * m00 + s[GV_YY] * m10
                l11 = (s[GV_YX] + s[GS_YX]) * m01 + gs11 * m11
                div_v = l00 + l11
                if not correct_strain:
                    # shear rate and spin from the plain kernel gradient (Bui et al. 2008): the
                    # corrected one excites a growing zig-zag mode at free surfaces. The
                    # normal rates keep the correction, so that the skeleton changes volume as the
                    # pore water of Eq. (24)-(25) sees it: where the support is cut (free
                    # surfaces, corners) the plain div v is about half the corrected one, the two
                    # phases would disagree on how much the soil expanded, and suction would
                    # grow at sheared corners
                    l01 = s[GV_XY]
                    l10 = s[GV_YX]
                    if scheme == SCHEME_NONE:
                        # dry: no pore water to agree with, and the corrected normal rates let a
                        # block that lands on a fixed floor eject free-surface particles
                        # (tests/test_parallel_runs.py's falling block), the same surface
                        # mode: the plain gradient throughout, as Bui et al. (2008)
                        l00 = gs00
                        l11 = gs11

                # effective stress: linear elastic, plane strain, Jaumann rate (Eq. 11)
                e01 = 0.5 * (l01 + l10)
                w = 0.5 * (l01 - l10)
                sxx = stress[i, 0]
                syy = stress[i, 1]
                sxy = stress[i, 3]
                stress[i, 0] = sxx + dt * ((lam + 2.0 * shear) * l00 + lam * l11 + 2.0 * w * sxy)
                stress[i, 1] = syy + dt * (lam * l00 + (lam + 2.0 * shear) * l11 - 2.0 * w * sxy)
                stress[i, 2] += dt * lam * (l00 + l11)
                stress[i, 3] = sxy + dt * (2.0 * shear * e01 + w * (syy - sxx))
                if plastic and row[MAT_PLASTIC] > 0.0:
                    r = dp_return(stress[i, 0], stress[i, 1], stress[i, 2], stress[i, 3],
                                  eps_soft[i], lam + 2.0 * shear / 3.0, shear,
                                  drucker_prager(row), eps_p[i])
                    stress[i, 0] = r[0]
                    stress[i, 1] = r[1]
                    stress[i, 2] = r[2]
                    stress[i, 3] = r[3]
                    eps_p[i] += r[5]
                    plastic_work[i] += r[6]
            else:
                mi = inverse_moment_3d(s, cm)
                lg = velocity_gradient_3d(s, cgv, cgs, mi, correct_strain,
                                          scheme == SCHEME_NONE)
                div_v = lg[0] + lg[4] + lg[8]
                jaumann_elastic_3d(stress, i, lg, lam, shear, dt)
                if plastic and row[MAT_PLASTIC] > 0.0:
                    r3 = dp_return_3d(stress[i, 0], stress[i, 1], stress[i, 2], stress[i, 3],
                                      stress[i, 4], stress[i, 5], eps_soft[i],
                                      lam + 2.0 * shear / 3.0, shear, drucker_prager(row),
                                      eps_p[i])
                    for c in range(6):
                        stress[i, c] = r3[c]
                    eps_p[i] += r3[7]
                    plastic_work[i] += r3[8]

            if scheme != SCHEME_NONE:
                if dim == 2:
                    # porosity rate, Eq. (24): trace(Gn Minv)
                    dn = s[GN_XX] * m00 + s[GN_XY] * m10 + s[GN_YX] * m01 + s[GN_YY] * m11
                    # corrected pressure gradient (Eq. 22) and the Eq. (23) correction term
                    gp0 = s[GP_X] * m00 + s[GP_Y] * m10
                    gp1 = s[GP_X] * m01 + s[GP_Y] * m11
                    q0 = s[Q_X]
                    q1 = s[Q_Y]
                    e_i = perm[i] * (gp0 * q0 + gp1 * q1)
                    # elevation head: div(k grad psi), psi = -rho_l b.x, with the same correction
                    head = s[SUM_APSI] + perm[i] * rho_l * (b0 * q0 + b1 * q1)
                    div_ka = 0.0
                    if acc_term:
                        div_ka = s[GA_XX] * m00 + s[GA_XY] * m10 + s[GA_YX] * m01 + s[GA_YY] * m11
                else:
                    dn = _trace_3d(s, cgn, mi)
                    gp0 = s[cgp] * mi[0] + s[cgp + 1] * mi[3] + s[cgp + 2] * mi[6]
                    gp1 = s[cgp] * mi[1] + s[cgp + 1] * mi[4] + s[cgp + 2] * mi[7]
                    gp2 = s[cgp] * mi[2] + s[cgp + 1] * mi[5] + s[cgp + 2] * mi[8]
                    q0, q1, q2 = s[cq], s[cq + 1], s[cq + 2]
                    e_i = perm[i] * (gp0 * q0 + gp1 * q1 + gp2 * q2)
                    head = s[capsi] + perm[i] * rho_l * (b0 * q0 + b1 * q1 + b2 * q2)
                    div_ka = _trace_3d(s, cga, mi) if acc_term else 0.0
                if drained_from[i] <= t:
                    p[i] = 0.0
                    p_prev[i] = 0.0
                elif scheme == SCHEME_EXPLICIT:
                    lap = s[cap_] - p[i] * s[ca] - e_i + head  # div(k grad(p + psi)), Eq. (23)
                    rate = bulk_water / poro[i] * (lap / gamma_l - div_v + inv_g * div_ka)
                    p_prev[i] = p[i]
                    p[i] += dt * rate
                elif scheme == SCHEME_PROJECTION:
                    pass  # p and p_prev were set by the pressure solve
                elif s[ca] > 0.0:
                    # TPI, Eq. (38) with B of Eq. (36); s[SUM_AP] holds sum A_ij p_j^(t+alpha)
                    b_i = -gamma_l * div_v + head + rho_l * div_ka - e_i
                    p_new = tpi_pressure(b_i, s[ca], s[cap_], p[i], beta, dt)
                    p_prev[i] = p[i]
                    p[i] = p_new
                if ponding > 0 and (p[i] > 0.0 or ponding == 2) and on_free_surface(s, cm, dim):
                    # a free-surface particle (its kernel support cut: the moment matrix of
                    # Eq. 22, free_surface.py) cannot hold positive pore pressure, nor any
                    # when drained
                    p[i] = 0.0
                    if p_prev[i] > 0.0 or ponding == 2:
                        p_prev[i] = 0.0
                n_new = poro[i] + dt * dn
                if n_new < row[MAT_N_MIN]:
                    # Eq. (24) alone lets a free-surface particle (p imposed, so no pressure
                    # feedback) drift to n <= 0, where K_l / n of Eq. (25) changes sign
                    n_new = row[MAT_N_MIN]
                set_porosity(i, n_new, poro, poro0, vol, vol0, rho, perm, row[MAT_RHO_S], rho_l,
                             row[MAT_K], row[MAT_C_K])

            if not kicked:
                _momentum(i, s, cdv, f, loads, b0, b1, b2, damping, dt, dim)
            for d in range(dim):
                x[i, d] += dt * v[i, d]
                u[i, d] += dt * v[i, d]
            if bad < 0:
                if not (abs(p[i]) < 1e300 and abs(v[i, 0]) < 1e300 and abs(v[i, 1]) < 1e300
                        and abs(stress[i, 0]) < 1e300 and abs(stress[i, 1]) < 1e300
                        and abs(stress[i, 3]) < 1e300):
                    bad = i
                elif dim == 2 and not (box[0] <= x[i, 0] <= box[2]
                                       and box[1] <= x[i, 1] <= box[3]):
                    bad = i
                elif dim == 3 and not (abs(v[i, 2]) < 1e300 and abs(stress[i, 2]) < 1e300
                                       and abs(stress[i, 4]) < 1e300
                                       and abs(stress[i, 5]) < 1e300
                                       and box[0] <= x[i, 0] <= box[3]
                                       and box[1] <= x[i, 1] <= box[4]
                                       and box[2] <= x[i, 2] <= box[5]):
                    bad = i
                elif scheme != SCHEME_NONE and not (0.0 < poro[i] < 1.0):
                    bad = i  # Eq. (24) left (0, 1): K_l / n or the volume changed sign
        return bad

    return advance


advance = make_advance(2)
advance_3d = make_advance(3)


@nb.njit(cache=True, inline="always")
def _trace_3d(s, c, mi):
    """trace(G Minv) of the 3x3 group G = s[c:c + 9] (row-major)."""
    acc = 0.0
    for a in range(3):
        for n in range(3):
            acc += s[c + 3 * a + n] * mi[3 * n + a]
    return acc

"""The argument bundles of the kernels with many arguments (the pair sweep
`interactions.pair_sums`, the update `update.advance` and the others whose arguments would
otherwise run past a dozen): named tuples of arrays and scalars, which numba passes at no
cost (a tuple's members are unboxed as separate arguments would be). A caller builds them
each call from the current arrays (a store that grows replaces its arrays), with the
scalars coerced to one type, so that one compiled specialisation serves every run.
"""

import math
from typing import NamedTuple

import numpy as np


class PairFields(NamedTuple):
    """The fields the pair sweep reads on both particles of a pair (rows 0..n_total-1:
    owned, halo, wall ghosts). v_slip: velocities with wall ghosts mirrored as on a
    free-slip wall; astress: artificial stress R (xx, yy, xy), (cap, 3)."""
    x: np.ndarray
    v: np.ndarray
    v_slip: np.ndarray
    stress: np.ndarray
    p: np.ndarray
    p_prev: np.ndarray
    poro: np.ndarray
    vol: np.ndarray
    rho: np.ndarray
    perm: np.ndarray
    acc: np.ndarray
    astress: np.ndarray


class Cells(NamedTuple):
    """Cell list of `neighbours.bin_particles`: rows order[cell_start[c]:cell_start[c + 1]]
    lie in cell c of the ncell[0] x ncell[1] (x ncell[2]) grid; x_sorted[s] = x[order[s]],
    the positions in slot order, so the sweep's distance tests read memory in sequence
    (`neighbours.gather_sorted`); owned_before[s] counts the owned rows in slots before s
    (`neighbours.count_owned`), so that a sweep skips runs of slots without one."""
    cell_start: np.ndarray
    order: np.ndarray
    ncell: np.ndarray
    x_sorted: np.ndarray
    owned_before: np.ndarray


def sorted_cells(cell_start: np.ndarray, order: np.ndarray, ncell: np.ndarray,
                 x: np.ndarray, n_owned: int | None = None) -> Cells:
    """`Cells` of a cell list and the positions it sorts (for tests and drivers; the time
    loop fills its own x_sorted).

    Parameters
    ----------
    cell_start, order, ncell : int64 arrays
        the cell list of `neighbours.bin_particles`.
    x : (n, dim) float64 array
        positions (m), indexed as `order`.
    n_owned : int, optional
        rows below it are owned (default: all).

    Returns
    -------
    Cells
    """
    n = int(cell_start[int(np.prod(ncell))])
    from psph.kernels.neighbours import count_owned

    before = np.zeros(n + 1, np.int64)
    count_owned(order, n, n if n_owned is None else n_owned, before)
    return Cells(cell_start, order, ncell, np.ascontiguousarray(x[order[:n]]), before)


class PairRecord(NamedTuple):
    """Where the sweep records its pairs (a, b) and grad_a W_ab, in visiting order."""
    pairs: np.ndarray
    pair_g: np.ndarray


class PairParams(NamedTuple):
    """Scalars of the pair sweep: smoothing length h (m); alpha of TPI's Eq. (39)
    (0 otherwise); Monaghan's av_alpha, av_beta and the sound speed c_sound (m/s) of
    C_ij in Eq. (26); rho_l times the body force (N/m^3); coupled: the pressure sums;
    acc_term: the div(k dv/dt) sums; as_n, w_dx: exponent and W(dx) of the artificial
    stress (as_n = 0: off); p_weight: share of p in the pair stress; record: write the
    pairs; rho_l_b2: rho_l b_z in 3D."""
    h: float
    tpi_alpha: float = 0.0
    av_alpha: float = 0.0
    av_beta: float = 0.0
    c_sound: float = 1.0
    rho_l_b0: float = 0.0
    rho_l_b1: float = 0.0
    coupled: bool = True
    acc_term: bool = False
    as_n: float = 0.0
    w_dx: float = 1.0
    p_weight: float = 1.0
    record: bool = False
    rho_l_b2: float = 0.0  # the body force's third component (3D)

    def typed(self) -> "PairParams":
        """The same values as the compiled types (float, bool), so that one compiled
        specialisation serves every call."""
        return PairParams(*(bool(v) if isinstance(d, bool) else float(v)
                            for v, d in zip(self, _PAIR_DEFAULTS, strict=True)))


_PAIR_DEFAULTS = PairParams(0.0)


class UpdateFields(NamedTuple):
    """The owned rows' fields `advance` reads and writes."""
    x: np.ndarray
    u: np.ndarray
    v: np.ndarray
    stress: np.ndarray
    p: np.ndarray
    p_prev: np.ndarray
    poro: np.ndarray
    poro0: np.ndarray
    vol: np.ndarray
    vol0: np.ndarray
    rho: np.ndarray
    perm: np.ndarray
    acc: np.ndarray
    drained_from: np.ndarray
    material: np.ndarray
    eps_p: np.ndarray
    plastic_work: np.ndarray


class SurfaceLoads(NamedTuple):
    """Surface loads: a particle's load index (-1: none) and traction area vector, and
    the loads' current values (Pa)."""
    load_index: np.ndarray
    traction: np.ndarray
    load_value: np.ndarray


class StepParams(NamedTuple):
    """Scalars of `advance`: dt (s), t (s), K_l (Pa), gamma_l = rho_l g (N/m^3), rho_l,
    body force (m/s^2), damping c_d of Eq. (44) (1/s), the pressure scheme (SCHEME_*),
    beta of Eq. (47), acc_term (div(k dv/dt)), correct_strain (the corrected shear
    rate), plastic (some material is Drucker-Prager), ponding (0, 1, 2), kicked (the
    symplectic step has advanced v already)."""
    dt: float
    t: float
    bulk_water: float
    gamma_l: float
    rho_l: float
    b0: float
    b1: float
    damping: float
    scheme: int
    beta: float
    acc_term: bool
    correct_strain: bool
    plastic: bool
    ponding: int
    kicked: bool
    b2: float = 0.0  # the body force's third component (3D)

    def typed(self) -> "StepParams":
        """The same values as the compiled types (float, int, bool), so that one compiled
        specialisation serves every call."""
        kinds = (float,) * 8 + (int, float, bool, bool, bool, int, bool, float)
        return StepParams(*(k(v) for k, v in zip(kinds, self, strict=True)))


def fields_of(cls, arrays: dict, **extra):
    """An array bundle from a store's arrays, by field name.

    Parameters
    ----------
    cls : NamedTuple class
        the bundle (`PairFields`, `UpdateFields`, ...).
    arrays : dict of str to array
        the store's arrays by field name.
    **extra : array
        members taken from here instead of `arrays`.

    Returns
    -------
    cls
    """
    return cls(**{name: extra[name] if name in extra else arrays[name]
                  for name in cls._fields})


class CellList(NamedTuple):
    """A cell list of `neighbours.bin_particles` with each row's cell: rows
    order[cell_start[c]:cell_start[c + 1]] lie in cell c of the ncell[0] x ncell[1]
    (x ncell[2]) grid, and row i in cell cell_of[i]."""
    cell_of: np.ndarray
    cell_start: np.ndarray
    order: np.ndarray
    ncell: np.ndarray


class NonlocalFields(NamedTuple):
    """The fields of the real rows (owned and halo) that the non-local strain
    (`nonlocal_strain.nonlocal_strain`) averages over: positions (m), volumes (m^3; m^2
    in 2D), the local equivalent plastic strain eps_p and each row's material index."""
    x: np.ndarray
    vol: np.ndarray
    eps_p: np.ndarray
    material: np.ndarray


class DruckerPrager(NamedTuple):
    """One material's Drucker-Prager law for the return mapping
    (`plasticity.dp_return_3d`): the peak and residual friction angles phi_p, phi_r (rad)
    and cohesions c_p, c_r (Pa), the initial dilatancy angle psi0 (rad), the softening
    rates eta (of phi and c) and s_f (of psi) of Eq. (17)-(19); the tension cut-off of
    the mean effective stress (Pa; inf: none, the apex c cot(phi) of Eq. 14 bounds it);
    mohr_coulomb: the cone through Mohr-Coulomb at the trial stress's Lode angle instead
    of Eq. (16)'s plane-strain cone."""
    phi_p: float
    phi_r: float
    c_p: float
    c_r: float
    psi0: float
    eta: float
    s_f: float
    tension: float = math.inf
    mohr_coulomb: bool = False


class PorosityFields(NamedTuple):
    """The fields that follow a particle's porosity (`update.set_porosity`): porosity and
    initial porosity, volume and initial volume (m^3; m^2 in 2D), mixture density
    (kg/m^3) and hydraulic conductivity (m/s)."""
    poro: np.ndarray
    poro0: np.ndarray
    vol: np.ndarray
    vol0: np.ndarray
    rho: np.ndarray
    perm: np.ndarray


class FluidParams(NamedTuple):
    """The pore fluid and the body force: rho_l (kg/m^3), gamma_l = rho_l g (N/m^3), the
    bulk modulus K_l (Pa) and the body force b0, b1[, b2] (m/s^2; b2 in 3D only)."""
    rho_l: float
    gamma_l: float
    bulk_water: float
    b0: float
    b1: float
    b2: float = 0.0


class ImageFields(NamedTuple):
    """The fields the images of the pressure operator read (`images.image_weights`):
    positions (m), hydraulic conductivity (m/s), mixture density (kg/m^3) and volumes
    (m^3; m^2 in 2D)."""
    x: np.ndarray
    perm: np.ndarray
    rho: np.ndarray
    vol: np.ndarray


class ImageWeights(NamedTuple):
    """Where `images.image_weights` writes the operator's weights with the images: per
    recorded pair the diagonal and off-diagonal weights (w + w*, w - w*), and per row
    the storage term that the row's own image is added to."""
    w_diag: np.ndarray
    w_off: np.ndarray
    storage: np.ndarray


class WallFields(NamedTuple):
    """The fields of every row (owned, halo, wall ghosts, boundary particles) that the wall
    ghosts (`ghosts.make_ghosts`) and the boundary particles (`boundary.boundary_state`,
    `boundary_3d.boundary_state_3d`) take from the soil near them: positions (m),
    velocities (m/s), the velocities mirrored as on a free-slip wall (m/s), effective
    stress (Pa), pore pressure now and one step back (Pa), porosity, volume (m^3; m^2 in
    2D), mixture density (kg/m^3), hydraulic conductivity (m/s), acceleration (m/s^2) and
    sort key."""
    x: np.ndarray
    v: np.ndarray
    v_slip: np.ndarray
    stress: np.ndarray
    p: np.ndarray
    p_prev: np.ndarray
    poro: np.ndarray
    vol: np.ndarray
    rho: np.ndarray
    perm: np.ndarray
    acc: np.ndarray
    key: np.ndarray


class Walls(NamedTuple):
    """The plane walls x[axis] = pos (m), one entry each: the soil on the side `sign`
    (+1: larger x[axis]), fixed (no slip) or free-slip, and drained (the pore pressure
    mirrored antisymmetrically, p = 0 on the plane) at this step."""
    axis: np.ndarray
    pos: np.ndarray
    sign: np.ndarray
    fixed: np.ndarray
    drained: np.ndarray


class GhostSources(NamedTuple):
    """Per row g of a wall ghost: src[g], the real row it mirrors, and sign[g], the sign
    that carries a pressure increment to it (-1 across a drained wall)."""
    src: np.ndarray
    sign: np.ndarray


class BoundaryRows(NamedTuple):
    """The store's rows first..first+n-1 of boundary particles: row first + r holds the
    boundary particle src[r] of the scene."""
    first: int
    n: int
    src: np.ndarray


class BoundaryPoints(NamedTuple):
    """The scene's boundary particles k, each with its wall's motion (`boundary.MOTION_*`),
    tan(phi_b) of its friction angle, whether it is drained, its unit normal into the soil,
    a point `foot` of its wall (m), weight_dv = tan(phi_b) g_n dt of the weight friction
    (m/s; 0: none) and half_weight = g_n dx / 2 (m^2/s^2; times rho, the normal stress in
    Pa that carries half a particle's weight)."""
    motion: np.ndarray
    tan_phi: np.ndarray
    drained: np.ndarray
    normal: np.ndarray
    foot: np.ndarray
    weight_dv: np.ndarray
    half_weight: np.ndarray


class ContactGrid(NamedTuple):
    """The cell list that `boundary.boundary_contact` looks a particle's cell up in: the
    global grid's origin (m) and the first cell `lo` of this rank's grid along each axis,
    with the cell list of `neighbours.bin_particles` (cell_start, order, ncell)."""
    origin: np.ndarray
    lo: np.ndarray
    ncell: np.ndarray
    cell_start: np.ndarray
    order: np.ndarray


class ContactFields(NamedTuple):
    """The fields `boundary.boundary_contact` reads and moves: positions (m), velocities
    (m/s) and displacements (m), which it changes on the owned rows, and the effective
    stress (Pa) and mixture density (kg/m^3) of the weight friction."""
    x: np.ndarray
    v: np.ndarray
    u: np.ndarray
    stress: np.ndarray
    rho: np.ndarray


class ScaledOperator(NamedTuple):
    """The pressure operator S of the projection (Eq. (29)) on the step's pairs, as
    `laplacian.apply_scaled` applies it: the pairs (a, b), the coefficients of
    `laplacian.operator_coefficients` (c_diag, c_off per pair, c_storage per row), the
    imposed rows (`fixed`) and the Jacobi preconditioner's diagonal."""
    pairs: np.ndarray
    c_diag: np.ndarray
    c_off: np.ndarray
    c_storage: np.ndarray
    fixed: np.ndarray
    diag: np.ndarray


class CGWork(NamedTuple):
    """Scratch vectors of the conjugate gradients (`psph.solver.pcg.PCGWork`): the
    residual r, the preconditioned residual u, its image w = S u, the search direction d
    and its image sd."""
    r: np.ndarray
    u: np.ndarray
    w: np.ndarray
    d: np.ndarray
    sd: np.ndarray


class DotWork(NamedTuple):
    """Scratch of the correctly rounded inner products, in the argument order of
    `exact_sum.chunked_dot`: row, terms and acc of its chunk accumulators, partials of
    `exact_sum.exact_dot`."""
    row: np.ndarray
    terms: np.ndarray
    acc: np.ndarray
    partials: np.ndarray

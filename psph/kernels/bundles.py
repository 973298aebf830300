"""The argument bundles of the step's two large kernels, `interactions.pair_sums` and
`update.advance`: named tuples of arrays and scalars, which numba passes at no cost (a
tuple's members are unboxed as separate arguments would be). A caller builds them each
call from the current arrays (a store that grows replaces its arrays), with the scalars
coerced to one type, so that one compiled specialisation serves every run.
"""

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

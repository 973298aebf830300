"""Structure-of-arrays particle state.

Rows 0..n_owned-1 are the particles this rank advances; then n_halo copies of neighbours'
particles; then n_ghost wall ghosts. Every field is a float64 array of shape (cap,) or
(cap, ncomp) allocated once with spare capacity and grown (never per step). A vector has
`dim` components; the effective stress 4 in 2D (xx, yy, zz, xy: plane strain) and 6 in
3D (xx, yy, zz, xy, yz, zx, the Voigt order of the snapshots).
"""

from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class Field:
    """A particle field: name, components, SI unit, meaning, and whether the pair loop reads
    it on neighbours (then it travels in halo messages and is mirrored on ghosts)."""

    name: str
    ncomp: int  # in 2D; VECTOR: dim components, STRESS: 4 in 2D, 6 in 3D
    unit: str
    description: str
    neighbour: bool


VECTOR = -1
STRESS = -2

_FIELDS: tuple[Field, ...] = (
    Field("key", 1, "1", "stable global particle id (exact in float64 below 2**53)", True),
    Field("x", VECTOR, "m", "position", True),
    Field("v", VECTOR, "m/s", "velocity", True),
    Field("stress", STRESS, "Pa", "effective stress xx, yy, zz, xy[, yz, zx] (tension "
          "positive)", True),
    Field("p", 1, "Pa", "pore-water pressure (compression positive)", True),
    Field("p_prev", 1, "Pa", "pore pressure one step back, for TPI Eq. (39)", True),
    Field("poro", 1, "1", "porosity n", True),
    Field("vol", 1, "m^2", "particle volume (per unit thickness in 2D; m^3 in 3D)", True),
    Field("rho", 1, "kg/m^3", "mixture density (1 - n) rho_s + n rho_l", True),
    Field("perm", 1, "m/s", "hydraulic conductivity k", True),
    Field("acc", VECTOR, "m/s^2", "acceleration of the last step", True),
    Field("dp_prev", 1, "Pa", "pressure increment p^(n-1) - p^(n-2), the projection's "
          "second-order warm start (pressure_solve.py)", False),
    Field("u", VECTOR, "m", "displacement from the initial position", False),
    Field("poro0", 1, "1", "initial porosity", False),
    Field("vol0", 1, "m^2", "initial volume", False),
    Field("eps_p", 1, "1", "equivalent plastic strain", False),
    Field("plastic_work", 1, "J/m^3", "dissipated plastic work sigma' : d eps_p, "
          "accumulated (Eq. 13-15 of Lian et al. 2023)", False),
    Field("drained_from", 1, "s", "time from which p = 0 is imposed (inf: never)", False),
    Field("surface", 1, "1", "1 on the loaded surface layer (settlement diagnostics)", False),
    Field("load_index", 1, "1", "index of the surface load acting on the particle, or -1", False),
    Field("traction", VECTOR, "m", "outward tributary area vector -n dA of a loaded particle",
          False),
    Field("material", 1, "1", "index of the particle's material in the scene's list "
          "(0: the one [material], or the first of [[materials]])", False),
)



def fields_of_dim(dim: int, recycle: int = 0) -> tuple[Field, ...]:
    """The fields with their component counts in `dim` dimensions; with `recycle` > 0
    (`pressure.recycle`, at least 2) the recycled guess's basis and its images
    (psph/solver/recycling.py), `recycle` columns each."""
    width = {VECTOR: dim, STRESS: 4 if dim == 2 else 6}
    fields = tuple(replace(f, ncomp=width.get(f.ncomp, f.ncomp)) for f in _FIELDS)
    if recycle > 0:
        fields += (Field("recycle_x", recycle, "1", "earlier pressure-solve corrections, "
                         "S-orthonormal (the recycled guess's basis)", False),
                   Field("recycle_sx", recycle, "Pa", "their images S x", False))
    return fields


FIELDS = fields_of_dim(2)
FIELD_BY_NAME = {f.name: f for f in FIELDS}
# fields added after checkpoint format 1 was fixed: zero when an older checkpoint lacks them
ADDED_FIELDS = ("dp_prev", "material", "plastic_work", "recycle_x", "recycle_sx")
NEIGHBOUR_FIELDS = tuple(f.name for f in FIELDS if f.neighbour)


class ParticleStore:
    """Owns the arrays; exposes them as attributes (`store.p`, `store.x`, ...)."""

    def __init__(self, capacity: int, dim: int = 2, recycle: int = 0):
        self.dim = dim
        self.fields = fields_of_dim(dim, recycle)
        self.cap = 0
        self.n_owned = 0
        self.n_halo = 0
        self.n_ghost = 0
        self.arrays: dict[str, np.ndarray] = {}
        self._allocate(max(int(capacity), 16))

    def _allocate(self, cap: int) -> None:
        old = self.arrays
        n_keep = self.n_owned + self.n_halo + self.n_ghost
        self.arrays = {}
        for f in self.fields:
            shape = (cap,) if f.ncomp == 1 else (cap, f.ncomp)
            a = np.zeros(shape)
            if f.name in old:
                a[:n_keep] = old[f.name][:n_keep]
            self.arrays[f.name] = a
            setattr(self, f.name, a)
        self.cap = cap
        self.all_rows = tuple(self._as2d(f.name) for f in self.fields)
        self.neighbour_rows = tuple(self._as2d(n) for n in NEIGHBOUR_FIELDS)
        self.row_width = sum(f.ncomp for f in self.fields)

    def _as2d(self, name: str) -> np.ndarray:
        a = self.arrays[name]
        return a.reshape(a.shape[0], -1)

    def ensure(self, rows: int) -> bool:
        """Grow (by 1.5x at least) so that `rows` rows fit; True if the arrays moved."""
        if rows <= self.cap:
            return False
        self._allocate(max(rows, int(1.5 * self.cap)))
        return True

    @property
    def n_real(self) -> int:
        return self.n_owned + self.n_halo

    @property
    def n_total(self) -> int:
        return self.n_owned + self.n_halo + self.n_ghost

    def owned(self, name: str) -> np.ndarray:
        return self.arrays[name][: self.n_owned]

    def load(self, data: dict[str, np.ndarray]) -> None:
        """Set the owned particles from full arrays (missing fields stay zero)."""
        n = len(next(iter(data.values())))
        self.n_halo = self.n_ghost = 0
        self.ensure(n + n // 4 + 64)
        self.n_owned = n
        for name, a in data.items():
            self.arrays[name][:n] = a

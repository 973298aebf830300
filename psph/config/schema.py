"""The scene schema: the TOML tables of a scene as pydantic models (`Scene` and its
sections). Unknown keys, wrong types and out-of-range values fail here; the rules between
keys are `psph.config.rules`, loading and `--set` overrides `psph.config.load`.
"""

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_serializer, model_validator

from psph.config.boundaries import Boundaries
from psph.config.materials import Material, NamedMaterial
from psph.config.rules import check_scene

Pos = Annotated[float, Field(gt=0)]
Vec2 = Annotated[list[float], Field(min_length=2, max_length=2)]

SIDES = ("left", "right", "bottom", "top")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, validate_default=True)


class Domain(_Model):
    """The box bounded by the walls (m)."""

    min: Vec2
    max: Vec2


class Block(_Model):
    """A rectangle of soil filled with particles on a square lattice."""

    min: Vec2
    max: Vec2
    material: str | None = None  # a [[materials]] name; default: the first material


class Polygon(_Model):
    """A polygon of soil (m): the lattice of the domain (spacing dx, anchored at
    domain.min) inside it is filled with particles."""

    vertices: Annotated[list[Vec2], Field(min_length=3)]
    material: str | None = None


class MeshGeometry(_Model):
    """Soil from any mesh file meshio reads: particles on the domain lattice inside its
    triangles and quads (2D, x-y plane)."""

    file: str
    material: str | None = None


class Layer(_Model):
    """Soil between two ground profiles of a cross-section (issue 16): the domain lattice
    points with bottom(x) <= z <= top(x). Each profile is [[x, z], ...] strictly
    increasing in x, or the path of a CSV file of x, z rows (psph/geometry/profiles.py)."""

    top: list[Vec2] | str
    bottom: list[Vec2] | str
    material: str | None = None


class Particles(_Model):
    dx: Pos
    h_factor: Annotated[float, Field(ge=1.0, le=2.0)] = 1.2  # h = 1.2 dx (Section 3.1)
    blocks: list[Block] = []
    polygons: list[Polygon] = []
    meshes: list[MeshGeometry] = []
    layers: list[Layer] = []




class Load(_Model):
    """Distributed normal pressure on the outer particle layer of one side (Pa)."""

    side: Literal["left", "right", "bottom", "top"] = "top"
    pressure: float
    history: Literal["ramp", "harmonic"] = "ramp"
    ramp: Annotated[float, Field(ge=0.0)] = 0.0  # s: linear rise to `pressure`, then hold
    omega: Annotated[float, Field(ge=0.0)] = 0.0  # rad/s: pressure * (1 - cos(omega t))
    range: Vec2 | None = None  # extent along the side (m); default: the whole side


class Pressure(_Model):
    """Pore-pressure update: explicit Eq. (25), TPI Eq. (38)-(39), a projection (one
    linear solve of Eq. 29 per step, psph/kernels/projection.py), or none (dry)."""

    scheme: Literal["tpi", "explicit", "projection", "none"] = "tpi"
    alpha: Annotated[float, Field(ge=0.0, le=1.0)] = 0.5
    R: Pos = 17.0  # TPI amplifier of the fluid time step, Eq. (40)
    beta: Annotated[float, Field(ge=0.0)] = 0.0  # Eq. (47) for p < 0 (paper: 0.04); 0: off
    explicit_until: Annotated[float, Field(ge=0.0)] = 0.0  # s: explicit Eq. (25) before this
    acceleration_term: bool = False  # div(k dv/dt)/g of Eq. (25)/(36); see README
    # free-surface particles: true: cannot hold positive pore pressure (ponding, Section
    # 4.4); "drained": p = 0 there (atmospheric, no suction either); false: no condition
    ponding: bool | Literal["drained"] = False
    # projection: relative residual of the conjugate-gradient solve, and its iteration cap
    tolerance: Annotated[float, Field(gt=0.0, lt=1.0)] = 1.0e-9
    max_iterations: Annotated[int, Field(ge=1)] = 2000
    # TPI: run a Delta t or alpha beyond the measured stability bound (`tpi_gain_limit`)
    allow_unstable: bool = False
    # where a drained side holds p = 0: "mirror" on its true surface (antisymmetric
    # ghosts or images, psph/solver/drainage.py), "layer" on its outer particle layer, dx/2 inside
    drained_boundary: Literal["mirror", "layer"] = "mirror"
    # the pore pressure in Eq. (26): "pair" (the paper's), or from pressure differences,
    # tried for issue 13 cause 12 and unstable at free corners (README); explicit/TPI only
    momentum: Literal["pair", "difference", "gradient", "closure"] = "pair"


class Time(_Model):
    end: Pos | None = None  # s; default: the last verification time
    dt: Pos | None = None  # s; default: Eq. (40)-(42)
    cfl_solid: Pos = 0.1  # C_CFL^s of Eq. (41)
    cfl_fluid: Pos = 0.1  # C_CFL^l of Eq. (42)
    allow_dt_above_solid_limit: bool = False
    # "euler": one pair sweep, rates from v^n; "symplectic": kick v first, then a second
    # (velocity-only) sweep gives the stress/pressure rates from v^(n+1), Eq. (27).
    # Default: "symplectic" with pressure.scheme "projection" (the one-sweep step has no
    # stable step with it, issue 39), "euler" otherwise
    integrator: Literal["euler", "symplectic"] | None = None


class Stabilisation(_Model):
    damping: Annotated[float, Field(ge=0.0)] = 0.0  # eta_d of Eq. (44)
    av_alpha: Annotated[float, Field(ge=0.0)] = 0.1  # artificial viscosity in C_ij, Eq. (26)
    av_beta: Annotated[float, Field(ge=0.0)] = 0.1
    # the viscosity's sound speed: "solid" sqrt(E / rho_s) of Eq. (41), or "undrained"
    # c_sp of Eq. (28), the speed of the coupled mode the explicit Eq. (25) carries
    av_sound_speed: Literal["solid", "undrained"] = "solid"
    corrected_strain_rate: bool = False  # Eq. (22) correction in the stress rate; README
    shepard_every: Annotated[int, Field(ge=0)] = 0  # m of Eq. (46): filter p every m steps
    # particle shifting down the concentration gradient, A of D = A h^2 |grad v| dt
    # (psph/kernels/shifting.py; issue 13, cause 12); 0: off
    shifting: Annotated[float, Field(ge=0.0)] = 0.0
    # with the Shepard step, also filter the effective stress (stress regularisation, the
    # paper's ref. [14]): the odd-even mode of sigma' has no other damping (issue 13)
    shepard_stress: bool = False
    # the stress filter's kernel: "shepard" (zeroth order, Eq. 46's sum) or "mls" (first
    # order, ref. [14]: linear stress fields kept, also at free surfaces)
    stress_filter: Literal["shepard", "mls"] = "shepard"
    # the porosity takes the elastic volumetric strain the stress filter moves, so that
    # sigma' and n of Eq. (24) carry the same strain (issue 13: without it a debris-front
    # particle compacted to n = 0.021 while the filter erased the stress that resisted it)
    stress_filter_porosity: bool = True
    # the porosity takes the strain the pressure filter (Eq. 46) moves, as if the filter
    # were a strain and not an exchange of pore water between neighbours. A tried variant
    # (issue 13, README cause 12), off: with ponding it is a ratchet at the free surface
    # (the filter raises a surface particle's p and compacts it, the clip p <= 0 removes
    # the p and keeps the compaction): K0 = 0.5 at 40 s, 365 particles below the flow
    # rule's porosity bound against 83 without it
    pressure_filter_porosity: bool = False
    # artificial stress in C_ij of Eq. (26) (refs. [11, 18]): epsilon and exponent n;
    # default epsilon: 0.5 for Drucker-Prager soil, 0 (off) for elastic
    artificial_stress: Annotated[float, Field(ge=0.0)] | None = None
    artificial_stress_n: Annotated[float, Field(gt=0.0)] = 2.55


class Output(_Model):
    times: list[Annotated[float, Field(ge=0.0)]] = []  # s
    interval: Annotated[float, Field(ge=0.0)] = 0.0  # s; 0: only `times` and the end
    history_interval: Pos = 1.0e-3  # s between diagnostics rows (settlement, energy)
    # points (m) whose nearest particle's p and u go into history.csv as p_<name>, ...
    probes: dict[str, Vec2] = {}


class Verification(_Model):
    # collapse: run-out, final height and back scarp in summary.json (psph.verify.collapse)
    reference: Literal["none", "terzaghi", "harmonic", "strip_footing", "collapse"] = "none"
    tv: list[Pos] = []  # time factors T_v at which to snapshot and compare


class Removal(_Model):
    """Particles inside a region at time `at` are removed from the run: the gate of a
    collapse, an excavated slope toe. The region is a box (min, max) or a polygon."""

    at: Annotated[float, Field(ge=0.0)] = 0.0  # s
    min: Vec2 | None = None
    max: Vec2 | None = None
    polygon: Annotated[list[Vec2], Field(min_length=3)] | None = None


class Initial(_Model):
    """In-situ state at t = 0 (Section 4.4-4.5): hydrostatic pore pressure below a water
    table, and the K0 procedure for the effective stress under gravity."""

    # m (elevation y): p = rho_l |g| (y_wt - y) below it; "surface": the water table
    # follows the ground surface (p = rho_l |g| depth below the top of each column); a
    # phreatic profile (issue 16): [[x, z], ...] or a CSV path, z_w(x) linear between its
    # points and held at its end values beyond them; p = 0 above it
    water_table: float | Literal["surface"] | list[Vec2] | str | None = None
    k0: Annotated[float, Field(gt=0.0)] | None = None  # sigma'_h = K0 sigma'_v; none: zero
    # s of gravity loading before t = 0 (Section 4.5): the skeleton relaxes from the K0
    # state to equilibrium under free faces, with p held hydrostatic and global damping
    # eta_d = equilibrate_damping (Eq. 43-44); then u = v = 0. 0: start from the K0 state
    equilibrate: Annotated[float, Field(ge=0.0)] = 0.0
    equilibrate_damping: Annotated[float, Field(gt=0.0)] = 0.1
    # start from the undrained response to the (single, full-side, step) load of a
    # laterally confined column: p0 = q / (1 + n M / K_l), sigma' = -(q - p0) along the
    # load, nu / (1 - nu) of it across (psph/physics/initial.py), as GeoTaichi starts its
    # Terzaghi column; the loading stage and its waves are then skipped
    undrained_load: bool = False


class Decomposition(_Model):
    axis: Literal["auto", "x", "y"] = "auto"
    # every this many steps the work imbalance (max/mean particles per rank) is measured;
    # 0: never (the slabs stay as cut at the start)
    rebalance_every: Annotated[int, Field(ge=0)] = 200
    # recut the slabs when the imbalance exceeds this
    imbalance_threshold: Annotated[float, Field(gt=1.0)] = 1.05


class Checkpoint(_Model):
    """Restart state in OUT/checkpoint.h5 (replaced atomically)."""

    every: Annotated[int, Field(ge=0)] = 0  # steps between checkpoints; 0: by wall time only
    wall_seconds: Annotated[float, Field(ge=0.0)] = 1800.0  # wall s between them; 0: off
    at_end: bool = True  # also write one when the run finishes


class Scene(_Model):
    name: str
    description: str = ""
    dim: Literal[2] = 2
    gravity: Vec2 = [0.0, 0.0]
    domain: Domain
    particles: Particles
    # one material (index 0), or several by name (issue 16, psph/config/materials.py); with
    # [[materials]], `material` is set to the first of them after validation (the fluid's
    # constants and the references read it) and left out of the dump
    material: Material | None = None
    materials: list[NamedMaterial] = []
    boundaries: Boundaries = Boundaries()
    loads: list[Load] = []
    pressure: Pressure = Pressure()
    time: Time = Time()
    stabilisation: Stabilisation = Stabilisation()
    output: Output = Output()
    verification: Verification = Verification()
    initial: Initial = Initial()
    remove: list[Removal] = []
    decomposition: Decomposition = Decomposition()
    checkpoint: Checkpoint = Checkpoint()

    @model_validator(mode="after")
    def _consistent(self) -> "Scene":
        return check_scene(self)

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        """With [[materials]], `material` (their first) is not written back; without them,
        no empty `materials` (the scene.toml of a one-material scene is as before)."""
        d = handler(self)
        if isinstance(d, dict):
            d.pop("material" if self.materials else "materials", None)
        return d

    @property
    def material_list(self) -> list[Material]:
        """The materials in index order (the per-particle `material` field indexes it)."""
        return list(self.materials) or [self.material]

    @property
    def h(self) -> float:
        return self.particles.h_factor * self.particles.dx


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
# a point or vector of the scene's dimension: [x, y] in 2D, [x, y, z] in 3D (the rules
# check the count against `dim`, `rules.check_dimension`)
Vec = Annotated[list[float], Field(min_length=2, max_length=3)]

SIDES = ("left", "right", "bottom", "top")
SIDES_3D = ("left", "right", "front", "back", "bottom", "top")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, validate_default=True)


class Domain(_Model):
    """The box bounded by the walls (m)."""

    min: Vec = Field(description="Lower corner of the domain box, [x, y] or [x, y, z] (its "
                     "length sets `dim` when dim is not given) [m]")
    max: Vec = Field(description="Upper corner of the domain box; must exceed min [m]")


class Block(_Model):
    """A rectangle (a box in 3D) of soil filled with particles on a square (cubic)
    lattice."""

    min: Vec = Field(description="Lower corner of the rectangle (box in 3D); its lattice "
                     "starts here [m]")
    max: Vec = Field(description="Upper corner of the rectangle (box); must exceed min [m]")
    material: str | None = Field(None, description="Name of a [[materials]] table; default "
                                 "the first material")


class Polygon(_Model):
    """A polygon of soil (m): the lattice of the domain (spacing dx, anchored at
    domain.min) inside it is filled with particles."""

    vertices: Annotated[list[Vec2], Field(min_length=3)] = Field(
        description="Polygon vertices [[x, y], ...], at least 3, inside the domain [m]")
    material: str | None = Field(None, description="Name of a [[materials]] table; default "
                                 "the first material")


class Sphere(_Model):
    """A ball of soil (3D): the domain lattice points within `radius` of `centre`; a
    domain box that cuts it through its centre with slip walls makes a half, quarter or
    eighth of it (Cryer's sphere as an octant)."""

    centre: Vec = Field(description="Centre [x, y, z] [m]")
    radius: Pos = Field(description="Radius [m]")
    material: str | None = Field(None, description="Name of a [[materials]] table; default "
                                 "the first material")


class Cylinder(_Model):
    """An upright cylinder of soil (3D): the domain lattice points within `radius` of the
    vertical axis through `base` and between base[2] and base[2] + height; slip walls
    through the axis make a half or a quarter of it (the axisymmetric collapse)."""

    base: Vec = Field(description="Centre of the base [x, y, z] [m]")
    radius: Pos = Field(description="Radius [m]")
    height: Pos = Field(description="Height [m]")
    material: str | None = Field(None, description="Name of a [[materials]] table; default "
                                 "the first material")


class MeshGeometry(_Model):
    """Soil from any mesh file meshio reads: particles on the domain lattice inside its
    triangles and quads (2D, x-y plane), or in 3D inside the volume a closed surface
    mesh (STL, OBJ, PLY, ...) bounds."""

    file: str = Field(description="Path of a mesh file meshio reads: 2D triangles/quads in "
                      "x-y, or in 3D a closed triangle/quad surface")
    material: str | None = Field(None, description="Name of a [[materials]] table; default "
                                 "the first material")


class Layer(_Model):
    """Soil between two ground profiles of a cross-section: the domain lattice
    points with bottom(x) <= z <= top(x). Each profile is [[x, z], ...] strictly
    increasing in x, or the path of a CSV file of x, z rows (psph/geometry/profiles.py)."""

    top: list[Vec2] | str = Field(description="Upper profile [[x, z], ...] strictly "
                                  "increasing in x, or a CSV path [m]")
    bottom: list[Vec2] | str = Field(description="Lower profile, nowhere above top, or a CSV "
                                     "path [m]")
    material: str | None = Field(None, description="Name of a [[materials]] table; default "
                                 "the first material")


class Particles(_Model):
    dx: Pos = Field(description="Lattice spacing of the particles [m]")
    h_factor: Annotated[float, Field(ge=1.0, le=2.0)] = Field(
        1.2, description="Smoothing length over spacing, h = h_factor dx (Section 3.1) [-]")
    blocks: list[Block] = Field([], description="Rectangles of soil, each on its own "
                                "lattice from its min")
    polygons: list[Polygon] = Field([], description="Polygons of soil on the domain lattice")
    meshes: list[MeshGeometry] = Field([], description="Mesh files (meshio) whose cells are "
                                       "filled with soil on the domain lattice")
    layers: list[Layer] = Field([], description="Soil between two ground profiles of a "
                                "cross-section, on the domain lattice")
    spheres: list[Sphere] = Field([], description="Balls of soil on the domain lattice "
                                  "(3D only)")
    cylinders: list[Cylinder] = Field([], description="Upright cylinders of soil on the "
                                      "domain lattice (3D only)")




class Load(_Model):
    """Distributed normal pressure on the outer particle layer of one side (Pa)."""

    side: Literal["left", "right", "front", "back", "bottom", "top", "surface"] = Field(
        "top", description="Side of the box the pressure acts on (front, back: 3D only), or "
        "\"surface\": every exposed lattice face of the soil not against a wall (a uniform "
        "confinement of any shape)")
    pressure: float = Field(description="Normal pressure on the side's outer layer: held "
                            "after the ramp, or the p of p (1 − cos ωt) [Pa]")
    history: Literal["ramp", "harmonic"] = Field(
        "ramp", description="Time history: \"ramp\" (rise, then hold) or \"harmonic\" "
        "(p (1 − cos ωt))")
    ramp: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Linear rise time to `pressure`, then hold; 0 is a step [s]")
    omega: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Angular frequency ω of the harmonic load, p (1 − cos ωt) [rad/s]")
    range: Vec2 | None = Field(None, description="Extent [from, to] along the side; default "
                               "the whole side [m]")


class Pressure(_Model):
    """Pore-pressure update: explicit Eq. (25), TPI Eq. (38)-(39), a projection (one
    linear solve of Eq. 29 per step, psph/kernels/projection.py), or none (dry)."""

    scheme: Literal["tpi", "explicit", "projection", "none"] = Field(
        "tpi", description="Pore-pressure scheme: \"tpi\" (Eq. 38–39), \"explicit\" (Eq. 25), "
        "\"projection\" (Eq. 29 solved) or \"none\" (dry)")
    alpha: Annotated[float, Field(ge=0.0, le=1.0)] = Field(
        0.5, description="TPI weight α of Eq. (39); above 0.75 needs pressure.allow_unstable "
        "[-]")
    R: Pos = Field(17.0, description="TPI step as a multiple of the fluid limit Eq. (42), "
                   "Eq. (40); capped by Eq. (41) and TPI's gain bound [-]")
    beta: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Storage β of Eq. (47) for p < 0; 0 is off (paper: 0.04) [-]")
    explicit_until: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Time until which TPI scenes run explicit Eq. (25) (the loading "
        "stage) [s]")
    # the relative acceleration of the water, Eq. (36); off in the paper's runs
    acceleration_term: bool = Field(False, description="Include div(k dv/dt)/g of "
                                    "Eq. (25)/(36)")
    # true: ponding, Section 4.4; "drained": atmospheric, no suction either
    ponding: bool | Literal["drained"] = Field(
        False, description="Free-surface condition: true p ≤ 0, \"drained\" p = 0, false none")
    tolerance: Annotated[float, Field(gt=0.0, lt=1.0)] = Field(
        1.0e-9, description="Relative residual of the projection's conjugate-gradient "
        "solve [-]")
    max_iterations: Annotated[int, Field(ge=1)] = Field(
        2000, description="Iteration cap of the projection's conjugate-gradient solve")
    recycle: Annotated[int, Field(ge=0, le=512)] = Field(
        0, description="Earlier CG corrections kept to project the projection's initial "
        "guess on (Fischer 1998); 0 is off, else at least 2; 16 L bytes a particle [-]")
    # `tpi_gain_limit`, bench/verification/stability.py
    allow_unstable: bool = Field(
        False, description="Run beyond the measured stability checks: TPI with α above "
        "0.75, a step above the gain bound or loading before any side drains; the "
        "projection with time.integrator \"euler\"")
    # antisymmetric ghosts or images, psph/solver/drainage.py
    drained_boundary: Literal["mirror", "layer"] = Field(
        "mirror", description="Where a drained side holds p = 0: \"mirror\" (its true "
        "surface) or \"layer\" (outer particle layer, dx/2 inside)")
    # the difference forms are unstable at free corners: experimental only
    momentum: Literal["pair", "difference", "gradient", "closure"] = Field(
        "pair", description="Pore-pressure term of Eq. (26): \"pair\" (paper) or the "
        "experimental \"difference\", \"gradient\", \"closure\"; explicit/TPI only")


class Time(_Model):
    end: Pos | None = Field(None, description="End time; default the last verification "
                            "time [s]")
    dt: Pos | None = Field(None, description="Time step; default from Eq. (40)–(42) [s]")
    cfl_solid: Pos = Field(0.1, description="Courant number C_CFL^s of Eq. (41) [-]")
    cfl_fluid: Pos = Field(0.1, description="Courant number C_CFL^l of Eq. (42) [-]")
    allow_dt_above_solid_limit: bool = Field(
        False, description="Allow time.dt above Eq. (41) and the explicit scheme's "
        "undrained limit")
    # the one-sweep step has no stable step with the projection
    integrator: Literal["euler", "symplectic"] | None = Field(
        None, description="\"euler\" (one pair sweep) or \"symplectic\" (kick, then a "
        "velocity sweep, Eq. 27); default \"symplectic\" with the projection (which "
        "refuses \"euler\"), \"euler\" otherwise")


class Stabilisation(_Model):
    damping: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Global damping ratio η_d of Eq. (44) [-]")
    av_alpha: Annotated[float, Field(ge=0.0)] = Field(
        0.1, description="Artificial viscosity α_Π in C_ij of Eq. (26) [-]")
    av_beta: Annotated[float, Field(ge=0.0)] = Field(
        0.1, description="Artificial viscosity β_Π in C_ij of Eq. (26) [-]")
    # "undrained": the speed of the coupled mode the explicit Eq. (25) carries
    av_sound_speed: Literal["solid", "undrained"] = Field(
        "solid", description="Sound speed of the viscosity: \"solid\" sqrt(E/ρ_s) of Eq. (41) "
        "or \"undrained\" (c_sp of Eq. 28)")
    # the corrected shear rate excites a zig-zag mode at free surfaces: off by default
    corrected_strain_rate: bool = Field(
        False, description="Apply the Eq. (22) correction to the shear rate and spin too")
    shepard_every: Annotated[int, Field(ge=0)] = Field(
        0, description="Steps m between Shepard filters of p, Eq. (46), and of σ' with "
        "shepard_stress (a dry scene filters σ' only); 0 is off")
    # psph/kernels/shifting.py
    shifting: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Particle-shifting coefficient A of D = A h^2 |grad v| dt; 0 is "
        "off [-]")
    # stress regularisation, the paper's ref. [14]: the odd-even mode of sigma' has no other
    # damping
    shepard_stress: bool = Field(
        False, description="Also filter the effective stress in the Shepard step")
    # "mls" keeps linear stress fields, also at free surfaces (ref. [14])
    stress_filter: Literal["shepard", "mls"] = Field(
        "shepard", description="Kernel of the stress filter: \"shepard\" (zeroth order, "
        "Eq. 46) or \"mls\" (first order)")
    # so that sigma' and n of Eq. (24) carry the same strain (without it a
    # debris-front particle compacted to n = 0.021 while the filter erased the stress that
    # resisted it)
    stress_filter_porosity: bool = Field(
        True, description="Move the porosity by the elastic volumetric strain the stress "
        "filter removes")
    # as if the filter were a strain and not an exchange of pore water between neighbours.
    # Off: with ponding it is a ratchet at the
    # free surface (the filter raises a surface particle's p and compacts it, the clip
    # p <= 0 removes the p and keeps the compaction): K0 = 0.5 at 40 s, 365 particles below
    # the flow rule's porosity bound against 83 without it
    pressure_filter_porosity: bool = Field(
        False, description="Move the porosity by the strain the pressure filter (Eq. 46) "
        "moves (experimental)")
    # refs. [11, 18]
    artificial_stress: Annotated[float, Field(ge=0.0)] | None = Field(
        None, description="Artificial-stress ε in C_ij of Eq. (26); default 0.5 for "
        "Drucker–Prager, 0 (off) for elastic [-]")
    artificial_stress_n: Annotated[float, Field(gt=0.0)] = Field(
        2.55, description="Exponent n of the artificial stress [-]")


class Output(_Model):
    times: list[Annotated[float, Field(ge=0.0)]] = Field(
        [], description="Times of extra snapshots [s]")
    interval: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Time between snapshots; 0 keeps only `times` and the end [s]")
    history_interval: Pos = Field(1.0e-3, description="Time between history.csv rows "
                                  "(settlement, energy, probes) [s]")
    probes: dict[str, Vec] = Field(
        {}, description="Named points whose nearest particle's p and u go into history.csv "
        "as p_<name>, ... [m]")


class Verification(_Model):
    # collapse: run-out, final height and back scarp in summary.json (psph.verify.collapse)
    reference: Literal["none", "terzaghi", "harmonic", "strip_footing", "collapse",
                       "cryer"] = Field(
        "none", description="Reference compared at the end: \"none\", \"terzaghi\", "
        "\"harmonic\", \"strip_footing\", \"collapse\", \"cryer\" (the probe \"centre\" "
        "against Cryer's series)")
    tv: list[Pos] = Field([], description="Time factors T_v at which to snapshot and "
                          "compare [-]")


class Trigger(_Model):
    """Failure triggered after the gravity loading, as del Castillo, Borja and Fávero Neto
    (2026, doi:10.1002/nag.70322) start their slopes: until `at` the soil keeps its peak
    strength and does not soften (η = 0, the loading at peak strength); at `at` the
    strength is divided by `strength_factor` (a strength-reduction factor) and softening
    starts at the material's η."""

    at: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Time of the trigger; 0 is the run's start, after "
        "initial.equilibrate [s]")
    strength_factor: Annotated[float, Field(ge=1.0)] = Field(
        1.0, description="Divides the peak cohesion and tan φ_p, and the residual ones "
        "unless reduce_residual = false [-]")
    reduce_residual: bool = Field(
        True, description="Divide the residual strength (c_r, tan φ_r) by strength_factor "
        "too")
    reset_plastic_strain: bool = Field(
        True, description="Set the equivalent plastic strain (and the plastic work) to 0 "
        "at the trigger")


class Removal(_Model):
    """Particles inside a region at time `at` are removed from the run: the gate of a
    collapse, an excavated slope toe, a river's cut. The region is a box (min, max) or a
    polygon: in 2D in the x-y plane, in 3D in plan (x, y), every particle above it or,
    with `depth`, those within `depth` of their dx x dx column's highest particle."""

    at: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Time the region's particles are removed [s]")
    min: Vec | None = Field(None, description="Lower corner of a box region (with max) "
                            "[m]")
    max: Vec | None = Field(None, description="Upper corner of a box region (with min) "
                            "[m]")
    polygon: Annotated[list[Vec2], Field(min_length=3)] | None = Field(
        None, description="Vertices of a polygon region, at least 3 (instead of min/max) [m]")
    depth: Pos | None = Field(
        None, description="3D polygon in plan: remove the particles within this depth of "
        "their dx x dx column's highest particle (default: the whole column) [m]")


class Initial(_Model):
    """In-situ state at t = 0 (Section 4.4-4.5): hydrostatic pore pressure below a water
    table, and the K0 procedure for the effective stress under gravity."""

    # a level (elevation y): p = rho_l |g| (y_wt - y) below it; "surface": the water table
    # follows the ground surface (p = rho_l |g| depth below the top of each column); a
    # phreatic profile: z_w(x) linear between its points and held at its end
    # values beyond them; p = 0 above it
    water_table: float | Literal["surface"] | list[Vec2] | str | None = Field(
        None, description="Water table: a level, \"surface\", or a phreatic profile "
        "[[x, z], ...]/CSV; hydrostatic p below it; none: p = 0 [m]")
    k0: Annotated[float, Field(gt=0.0)] | None = Field(
        None, description="Earth-pressure coefficient, σ'_h = K0 σ'_v; none leaves zero "
        "effective stress [-]")
    # Section 4.5: the skeleton relaxes from the K0 state to equilibrium under free faces,
    # with global damping (Eq. 43-44); then u = v = 0
    equilibrate: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Gravity loading before t = 0 with p held hydrostatic; 0 starts "
        "from the K0 state [s]")
    equilibrate_damping: Annotated[float, Field(gt=0.0)] = Field(
        0.1, description="Damping ratio η_d during the gravity loading [-]")
    # of a laterally confined column: p0 = q / (1 + n M / K_l), sigma' = -(q - p0) along
    # the load, nu / (1 - nu) of it across (psph/physics/initial.py), as GeoTaichi starts
    # its Terzaghi column; the loading stage and its waves are then skipped
    undrained_load: bool = Field(
        False, description="Start from the undrained response to the single full-side step "
        "load")


class Decomposition(_Model):
    axis: Literal["auto", "x", "y", "z"] = Field(
        "auto", description="Slab axis: \"auto\" (the domain's longest side), \"x\", \"y\" "
        "or, in 3D, \"z\"")
    cuts: Literal["auto", "slabs", "boxes"] = Field(
        "auto", description="\"slabs\" along `axis`; \"boxes\": slabs cut again along the "
        "particles' next longest side (two axes); \"auto\": boxes where their "
        "busiest rank holds less halo than the slabs' (4 or more ranks)")
    rebalance_every: Annotated[int, Field(ge=0)] = Field(
        200, description="Steps between imbalance checks; 0 is never (the slabs stay as "
        "cut at the start)")
    imbalance_threshold: Annotated[float, Field(gt=1.0)] = Field(
        1.05, description="Max/mean particles per rank above which the slabs are recut [-]")


class Checkpoint(_Model):
    """Restart state in OUT/checkpoint.h5 (replaced atomically)."""

    every: Annotated[int, Field(ge=0)] = Field(
        0, description="Steps between checkpoints; 0 is by wall time only")
    wall_seconds: Annotated[float, Field(ge=0.0)] = Field(
        1800.0, description="Wall time between checkpoints; 0 is off [s]")
    at_end: bool = Field(True, description="Also write a checkpoint when the run finishes")


class Scene(_Model):
    name: str = Field(description="Scene name; the default output directory is runs/<name>")
    description: str = Field("", description="One line describing the scene (printed by "
                             "`psph list`)")
    dim: Literal[2, 3] = Field(2, description="Spatial dimension: 2 (plane strain, vertical "
                               "y) or 3 (vertical z); default the length of domain.min")
    gravity: Vec | None = Field(None, description="Gravitational acceleration [g_x, g_y] "
                                "([g_x, g_y, g_z] in 3D); along the vertical, −y (−z), for "
                                "initial.k0 and water_table; default zero [m/s^2]")
    domain: Domain = Field(description="The box bounded by the walls")
    particles: Particles = Field(description="Particle spacing, smoothing length and the soil "
                                 "sources")
    # with [[materials]], `material` is set to the first of them after validation (the
    # fluid's constants and the references read it) and left out of the dump
    material: Material | None = Field(
        None, description="The single material (index 0); give it or [[materials]], not "
        "both")
    materials: list[NamedMaterial] = Field(
        [], description="Several named materials, picked by each source's "
        "`material`")
    boundaries: Boundaries = Field(Boundaries(), description="The four box sides and the "
                                   "polyline boundaries")
    loads: list[Load] = Field([], description="Distributed normal pressures on the box sides")
    pressure: Pressure = Field(Pressure(), description="Pore-pressure scheme and its "
                               "parameters")
    time: Time = Field(Time(), description="End time, step and integrator")
    stabilisation: Stabilisation = Field(Stabilisation(), description="Damping, viscosity, "
                                         "filters and shifting")
    output: Output = Field(Output(), description="Snapshot times, history interval and "
                           "probes")
    verification: Verification = Field(Verification(), description="Reference solution "
                                       "compared at the end of the run")
    initial: Initial = Field(Initial(), description="In-situ state at t = 0")
    remove: list[Removal] = Field([], description="Regions of soil removed at given times")
    trigger: Trigger | None = Field(None, description="Strength reduction and the start of "
                                    "softening after the gravity loading")
    decomposition: Decomposition = Field(Decomposition(), description="Slab axis and load "
                                         "balancing")
    checkpoint: Checkpoint = Field(Checkpoint(), description="When restart checkpoints are "
                                   "written")

    @model_validator(mode="before")
    @classmethod
    def _dimension(cls, data):
        """`dim` from the domain's corner when the scene does not give it."""
        if isinstance(data, dict) and "dim" not in data:
            lo = data.get("domain", {}).get("min") if isinstance(data.get("domain"), dict) \
                else None
            if isinstance(lo, list) and len(lo) == 3:
                data = {**data, "dim": 3}
        return data

    @model_validator(mode="after")
    def _consistent(self) -> "Scene":
        if self.gravity is None:
            self.gravity = [0.0] * self.dim
        return check_scene(self)

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        """With [[materials]], `material` (their first) is not written back; without them,
        no empty `materials` (the scene.toml of a one-material scene is as before); a 2D
        scene has no front or back side."""
        d = handler(self)
        if isinstance(d, dict):
            d.pop("material" if self.materials else "materials", None)
            if self.dim == 2 and isinstance(d.get("boundaries"), dict):
                d["boundaries"].pop("front", None)  # the 3D-only sides
                d["boundaries"].pop("back", None)
        return d

    @property
    def material_list(self) -> list[Material]:
        """The materials in index order (the per-particle `material` field indexes it)."""
        return list(self.materials) or [self.material]

    @property
    def h(self) -> float:
        return self.particles.h_factor * self.particles.dx


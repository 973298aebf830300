"""TOML scene -> validated, fully resolved `Scene`.

Layers: model defaults < scene file < `--set key.path=value`. Unknown keys, wrong types and
out-of-range values raise `SceneError` with one line naming the key, the value and the rule.
"""

import math
import tomllib
from pathlib import Path
from typing import Annotated, Literal

import tomli_w
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    model_serializer,
    model_validator,
)

from psph.errors import SceneError
from psph.errors import SceneRule as _Rule
from psph.limits import (  # noqa: F401  (re-exported: psph.scene.solid_dt_limit etc.)
    TPI_ALPHA_MAX,
    fluid_dt_limit,
    solid_dt_limit,
    tpi_dt,
    tpi_gain,
    tpi_gain_dt_limit,
    tpi_gain_limit,
    undrained_dt_limit,
)
from psph.scene_boundaries import Boundaries, Boundary, Polyline  # noqa: F401  (re-exported)
from psph.scene_material import (  # noqa: F401  (re-exported)
    Material,
    NamedMaterial,
    Plasticity,
    check_materials,
)

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
    increasing in x, or the path of a CSV file of x, z rows (psph/scenes/profiles.py)."""

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
    # ghosts or images, psph/drainage.py), "layer" on its outer particle layer, dx/2 inside
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
    # one material (index 0), or several by name (issue 16, psph/scene_material.py); with
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
        lo, hi = self.domain.min, self.domain.max
        for d in range(2):
            if hi[d] <= lo[d]:
                raise _Rule(f"domain.max[{d}]", hi[d], f"must exceed domain.min[{d}] = {lo[d]}")
        pa = self.particles
        if not (pa.blocks or pa.polygons or pa.meshes or pa.layers):
            raise _Rule("particles", "no blocks, polygons, meshes or layers",
                        "give at least one [[particles.blocks]], [[particles.polygons]], "
                        "[[particles.meshes]] or [[particles.layers]]")
        for il, layer in enumerate(pa.layers):
            check_layer_profiles(layer, f"particles.layers[{il}]")
        for ip, poly in enumerate(pa.polygons):
            for iv, v in enumerate(poly.vertices):
                for d in range(2):
                    if not lo[d] - 1e-12 <= v[d] <= hi[d] + 1e-12:
                        raise _Rule(f"particles.polygons[{ip}].vertices[{iv}]", v,
                                    f"outside the domain [{lo}, {hi}]")
        for ir, rm in enumerate(self.remove):
            box = rm.min is not None and rm.max is not None
            if box == (rm.polygon is not None) or (rm.min is None) != (rm.max is None):
                raise _Rule(f"remove[{ir}]", "region", "give either min and max, or polygon")
        for im, mesh in enumerate(pa.meshes):
            if not Path(mesh.file).is_file():
                raise _Rule(f"particles.meshes[{im}].file", mesh.file, "no such file")
        for ib, b in enumerate(self.particles.blocks):
            for d in range(2):
                if b.max[d] <= b.min[d]:
                    raise _Rule(f"particles.blocks[{ib}].max[{d}]", b.max[d],
                                f"must exceed particles.blocks[{ib}].min[{d}] = {b.min[d]}")
                if b.min[d] < lo[d] - 1e-12:
                    raise _Rule(f"particles.blocks[{ib}].min[{d}]", b.min[d],
                                f"particles outside the walls (domain.min[{d}] = {lo[d]})")
                if b.max[d] > hi[d] + 1e-12:
                    raise _Rule(f"particles.blocks[{ib}].max[{d}]", b.max[d],
                                f"particles outside the walls (domain.max[{d}] = {hi[d]})")
        mats = check_materials(self)
        if self.material is None:
            self.material = mats[0]
        table = self.initial.water_table
        if table is not None and table != "surface":
            from psph.scenes.profiles import ProfileError, check_water_table

            try:
                check_water_table(table, self.domain.min, self.domain.max)
            except ProfileError as e:
                where = "" if e.where in ("points", "file", "level") else f" {e.where}"
                raise _Rule(f"initial.water_table{where}", e.value, e.rule) from None
        if (self.initial.k0 is not None or self.initial.water_table is not None) \
                and self.gravity[1] >= 0.0:
            key = "initial.k0" if self.initial.k0 is not None else "initial.water_table"
            raise _Rule(key, getattr(self.initial, key.split(".")[1]),
                        f"needs gravity along -y (gravity = {self.gravity})")
        if self.initial.undrained_load:
            self._check_undrained_load()
        for name, pt in self.output.probes.items():
            for d in range(2):
                if not lo[d] <= pt[d] <= hi[d]:
                    raise _Rule(f"output.probes.{name}", pt,
                                f"probe outside the domain [{lo}, {hi}]")
        if self.pressure.scheme == "projection" and self.boundaries.polylines:
            raise _Rule("pressure.scheme", "projection", "not yet with boundaries.polylines")
        if self.pressure.momentum != "pair" and self.pressure.scheme not in ("explicit", "tpi"):
            raise _Rule("pressure.momentum", self.pressure.momentum,
                        "needs pressure.scheme 'explicit' or 'tpi' (the projection's velocity "
                        "correction is pair-symmetric)")
        if self.verification.reference == "terzaghi":
            self._check_terzaghi_reference()
        if self.time.end is None:
            if self.verification.reference == "none" or not self.verification.tv:
                raise _Rule("time.end", None, "required (no verification.tv to derive it from)")
        if self.time.dt is not None and not self.time.allow_dt_above_solid_limit:
            limit = solid_dt_limit(self)
            if self.time.dt > limit:
                raise _Rule("time.dt", self.time.dt,
                            f"above the solid limit Eq. (41) {limit:.3e} s "
                            "(set time.allow_dt_above_solid_limit = true to force)")
            if self.pressure.scheme == "explicit" and self.time.dt > undrained_dt_limit(self):
                raise _Rule("time.dt", self.time.dt,
                            f"above the undrained wave limit {undrained_dt_limit(self):.3e} s "
                            "of the explicit pressure update (Eq. 41 with the undrained "
                            "modulus; set time.allow_dt_above_solid_limit = true to force)")
        if self.pressure.scheme == "tpi" and not self.pressure.allow_unstable:
            self._check_tpi_stability()
        if self.time.integrator is None:
            self.time.integrator = "symplectic" if self.pressure.scheme == "projection" \
                else "euler"
        if self.pressure.scheme == "projection" and self.time.integrator == "euler" \
                and not self.pressure.allow_unstable:
            raise _Rule("time.integrator", "euler",
                        "has no stable step with pressure.scheme 'projection' (the one-sweep "
                        "step is forward Euler for the skeleton: it grew at 0.25 to 2 x Eq. "
                        "(41), bench/projection_stability.py); use 'symplectic', stable to "
                        f"Eq. (41) {solid_dt_limit(self):.3e} s (pressure.allow_unstable = "
                        "true to force)")
        return self

    def _check_terzaghi_reference(self) -> None:
        """What `verify.terzaghi.from_scene` reads: a load on the top, one drainage time."""
        key = "verification.reference"
        if not self.loads or self.loads[0].side != "top":
            raise _Rule(key, "terzaghi", "needs a [[loads]] entry on the top side first")
        ends = {getattr(self.boundaries, s).drained_from for s in ("top", "bottom")
                if getattr(self.boundaries, s).flow == "drained"}
        if len(ends) > 1:
            raise _Rule(key, "terzaghi", "needs the top and the bottom drained from the same "
                        f"time (boundaries.top/bottom.drained_from: {sorted(ends)})")

    def _check_undrained_load(self) -> None:
        """`initial.undrained_load` is the oedometric state of one step load over a side."""
        key = "initial.undrained_load"
        if len(self.loads) != 1:
            raise _Rule(key, True, f"needs exactly one [[loads]] (got {len(self.loads)})")
        load = self.loads[0]
        if load.history != "ramp" or load.ramp != 0.0 or load.range is not None:
            raise _Rule(key, True, "needs a step load over the whole side (loads[0]: history "
                        "= 'ramp', ramp = 0, no range)")
        if any(self.gravity) or self.initial.k0 is not None or \
                self.initial.water_table is not None:
            raise _Rule(key, True, "needs gravity = [0, 0] and no initial.k0 or water_table")
        if self.pressure.scheme == "none":
            raise _Rule(key, True, "needs pore water (pressure.scheme is 'none')")
        if len(self.materials) > 1:
            raise _Rule(key, True, "needs a single material (the column's own modulus)")

    def _check_tpi_stability(self) -> None:
        """TPI needs somewhere to drain, and the measured bounds of Eq. (38)-(39): alpha <=
        0.75 and G <= `tpi_gain_limit`."""
        force = "set pressure.allow_unstable = true to force"
        drained = [getattr(self.boundaries, side).drained_from
                   for side in ("left", "right", "bottom", "top")
                   if getattr(self.boundaries, side).flow == "drained"]
        if self.loads and self.pressure.ponding != "drained" and \
                self.pressure.explicit_until < min(drained, default=math.inf):
            raise _Rule("pressure.explicit_until", self.pressure.explicit_until,
                        "TPI loading while no side is drained: Eq. (38) has no storage term, "
                        "so with every side impermeable it fixes p only up to a constant and "
                        "the undrained loading blows up (the terzaghi column at 1.1 ms); run "
                        "the explicit scheme until the first side drains "
                        f"({min(drained, default=math.inf)} s); {force}")
        alpha = self.pressure.alpha
        if alpha > TPI_ALPHA_MAX:
            raise _Rule("pressure.alpha", alpha,
                        f"TPI is unstable for alpha above {TPI_ALPHA_MAX} at every R measured "
                        f"(bench/stability.py; the paper: above 0.75 at R = 98); {force}")
        dt = tpi_dt(self)
        gravity = any(g != 0.0 for g in self.gravity)
        gain, limit = tpi_gain(self, dt), tpi_gain_limit(alpha, gravity)
        if gain > limit:
            key, value = ("time.dt", dt) if self.time.dt is not None else \
                ("pressure.R", self.pressure.R)
            rule = "1.15 (1 - alpha)" if gravity else "min(5 (1 - alpha)^2, 3.6)"
            bench = "bench/tpi_gravity.py" + ("" if gravity else " --no-gravity")
            raise _Rule(key, value,
                        f"TPI gain G = dt gamma_l / (rho k) = {gain:.3g} at dt = {dt:.3e} s "
                        f"is above its stability bound {rule} = {limit:.3g} ({bench}): "
                        f"dt <= {dt * limit / gain:.3e} s; {force}")

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


def check_layer_profiles(layer: Layer, key: str):
    """Both profiles readable and increasing in x, the bottom nowhere above the top;
    returns their (k, 2) points. Raises _Rule naming the key, the value and the rule."""
    from psph.scenes.profiles import ProfileError, check_layer, read_profile

    points = {}
    for side in ("top", "bottom"):
        value = getattr(layer, side)
        try:
            points[side] = read_profile(value)
        except ProfileError as e:
            where = f"{key}.{side}" + ("" if e.where in ("points", "file") else f" {e.where}")
            raise _Rule(where, e.value, e.rule) from None
    try:
        check_layer(points["top"], points["bottom"])
    except ProfileError as e:
        raise _Rule(f"{key}.bottom", e.value, e.rule) from None
    return points["top"], points["bottom"]


# ---------------------------------------------------------------------------- loading


def run_scene(out: Path) -> "Scene":
    """The validated scene a run wrote to OUT/scene.toml (OSError, SceneError)."""
    path = Path(out) / "scene.toml"
    return validate(tomllib.loads(path.read_text()), str(path))


def builtin_dir() -> Path:
    return Path(__file__).parent / "scenes"


def builtin_names() -> list[str]:
    return sorted(p.stem for p in builtin_dir().glob("*.toml"))


def read_scene_text(source: str) -> tuple[str, str]:
    """(TOML text, label) for a built-in name or a file path."""
    if source in builtin_names():
        path = builtin_dir() / f"{source}.toml"
    else:
        path = Path(source)
        if not path.is_file():
            known = ", ".join(builtin_names())
            raise SceneError(f"scene '{source}': no such file or built-in scene ({known})")
    try:
        return path.read_text(), str(path)
    except OSError as e:
        raise SceneError(f"scene '{source}': cannot read: {e.strerror}") from None


def parse_toml(text: str, label: str) -> dict:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"{label}: not valid TOML: {e}") from None


def apply_override(data: dict, assignment: str) -> None:
    """Apply one `key.path=value` (value in TOML syntax; bare words are strings)."""
    if "=" not in assignment:
        raise SceneError(f"--set '{assignment}': expected key.path=value")
    path, raw = (s.strip() for s in assignment.split("=", 1))
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    keys = path.split(".")
    node = data
    for i, k in enumerate(keys[:-1]):
        nxt = int(k) if isinstance(node, list) and k.isdigit() else k
        try:
            node = node[nxt]
        except (KeyError, IndexError, TypeError):
            if isinstance(node, dict):
                node[nxt] = {}
                node = node[nxt]
            else:
                raise SceneError(f"--set {path}: '{'.'.join(keys[:i + 1])}' does not exist") \
                    from None
    last = keys[-1]
    if isinstance(node, list) and last.isdigit():
        if int(last) >= len(node):
            raise SceneError(f"--set {path}: index {last} out of range")
        node[int(last)] = value
    elif isinstance(node, dict):
        node[last] = value
    else:
        raise SceneError(f"--set {path}: '{'.'.join(keys[:-1])}' is not a table")


def _loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def validate(data: dict, label: str = "scene") -> Scene:
    """Validate a raw scene dict; on the first problem raise SceneError (one line)."""
    try:
        return Scene.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        ctx_err = (err.get("ctx") or {}).get("error")
        if isinstance(ctx_err, _Rule):
            raise SceneError(f"{label}: {ctx_err.key} = {ctx_err.value!r}: {ctx_err.rule}") \
                from None
        key = _loc(err["loc"])
        if err["type"] == "extra_forbidden":
            raise SceneError(f"{label}: unknown key '{key}'") from None
        if err["type"] == "missing":
            raise SceneError(f"{label}: {key}: required key is missing") from None
        value = err.get("input")
        rule = err["msg"][0].lower() + err["msg"][1:]
        raise SceneError(f"{label}: {key} = {value!r}: {rule}") from None


def load_scene(source: str, overrides: list[str] | None = None) -> Scene:
    """Built-in name or path -> validated, fully resolved Scene."""
    text, label = read_scene_text(source)
    data = parse_toml(text, label)
    for ov in overrides or []:
        apply_override(data, ov)
    scene = validate(data, label)
    return resolve(scene)


def resolve(scene: Scene) -> Scene:
    """Fill values derived from others (end time from the verification times, artificial
    stress from the material model)."""
    if scene.stabilisation.artificial_stress is None:
        scene = scene.model_copy(deep=True)
        scene.stabilisation.artificial_stress = \
            0.5 if any(m.model == "drucker_prager" for m in scene.material_list) else 0.0
    if scene.time.end is None:
        from psph.verify import reference_times

        t = reference_times(scene)
        scene = scene.model_copy(deep=True)
        scene.time.end = float(max(t))
    return scene


def to_toml(scene: Scene) -> str:
    return tomli_w.dumps(scene.model_dump(exclude_none=True))

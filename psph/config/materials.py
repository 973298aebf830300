"""The soil materials of a scene (Section 2.2 of Lian et al. 2023): one `[material]`
table, or several `[[materials]]` tables by name that the particle sources pick with
`material = "name"`. Validation raises `_Rule` (key, value, rule), which
`psph.config.load.validate` turns into one line and exit 2."""

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from psph.errors import SceneRule as _Rule

Pos = Annotated[float, Field(gt=0)]

# the pore fluid is one fluid: these keys must agree across the materials
FLUID_KEYS = ("rho_l", "K_l", "g_ref")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, validate_default=True)


class Regularisation(_Model):
    """Regularised (mesh-objective) softening: Eq. (17)-(19) driven by the
    over-non-local equivalent plastic strain eps_hat = (1 - m) eps_p + m eps_bar, eps_bar
    the average of eps_p with the cubic spline of smoothing length `length` (support
    2 length; psph/kernels/nonlocal_strain.py). `length` is the internal length l_c in
    metres, a material property independent of dx; m = 1: the plain average."""

    kind: Literal["nonlocal"] = Field(description="Regularisation kind (only \"nonlocal\")")
    length: Annotated[float, Field(gt=0.0)] = Field(
        description="Internal length l_c, the smoothing length of the non-local average "
        "(support 2 l_c), independent of dx [m]")
    m: Annotated[float, Field(ge=1.0)] = Field(
        2.0, description="Over-non-local weight m of eps_hat = (1 − m) eps_p + m eps_bar; 1 is "
        "the plain average [-]")


class Plasticity(_Model):
    """Drucker-Prager strain softening, Eq. (14)-(19). Angles in degrees, cohesion in Pa;
    residual values default to the peak ones (no softening)."""

    phi: Annotated[float, Field(ge=0.0, lt=90.0)] = Field(
        description="Peak friction angle φ_p, Eq. (14) [deg]")
    phi_r: Annotated[float, Field(ge=0.0, lt=90.0)] | None = Field(
        None, description="Residual friction angle, Eq. (17); default phi [deg]")
    c: Annotated[float, Field(ge=0.0)] = Field(0.0, description="Peak cohesion c_p [Pa]")
    c_r: Annotated[float, Field(ge=0.0)] | None = Field(
        None, description="Residual cohesion, Eq. (18); default c [Pa]")
    psi: Annotated[float, Field(gt=-90.0, lt=90.0)] = Field(
        0.0, description="Initial dilation angle ψ0, Eq. (19) [deg]")
    eta: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Softening rate of φ and c with plastic strain, Eq. (17)–(18); 0 is "
        "no softening [-]")
    s_f: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Decay rate of the dilation angle, Eq. (19); 0 keeps ψ0 [-]")
    regularisation: Regularisation | None = Field(
        None, description="Non-local softening of Eq. (17)–(19), so that a shear band's "
        "width is set by an internal length, not by dx; none keeps the local law")
    # in 3D the plane-strain cone of Eq. (16) is a third weaker in triaxial compression
    surface: Literal["plane_strain", "mohr_coulomb"] = Field(
        "plane_strain", description="Yield cone: \"plane_strain\", Eq. (16)'s fit (the "
        "paper's); \"mohr_coulomb\", the cone through Mohr–Coulomb at each stress's Lode "
        "angle (the same φ and c in every stress state, for 3D)")
    # none is the paper's law; 0 keeps a contractive soil at low confinement from
    # moving its total stress onto the pore water
    tension_cutoff: Annotated[float, Field(ge=0.0)] | None = Field(
        None, description="Largest mean effective stress σ'_m carried (tension positive); "
        "none keeps the apex c cot φ of Eq. (14) [Pa]")


class Material(_Model):
    """Saturated soil, linear elastic or elastic-plastic (Section 2.2; units Pa, kg/m^3,
    m/s)."""

    model: Literal["elastic", "drucker_prager"] = Field(
        "elastic", description="Constitutive model: \"elastic\" or \"drucker_prager\"")
    plasticity: Plasticity | None = Field(
        None, description="Drucker–Prager parameters; required with model = "
        "\"drucker_prager\", only with it")
    E: Pos = Field(description="Young's modulus of the skeleton [Pa]")
    nu: Annotated[float, Field(gt=-1.0, lt=0.5)] = Field(
        description="Poisson's ratio of the skeleton [-]")
    porosity: Annotated[float, Field(gt=0.0, lt=1.0)] = Field(
        description="Initial porosity n0; must be above porosity_min [-]")
    rho_s: Pos = Field(description="Density of the solid grains [kg/m^3]")
    rho_l: Pos = Field(1000.0, description="Density of the pore water; equal in all "
                       "materials [kg/m^3]")
    K_l: Pos = Field(1.0e9, description="Bulk modulus of the pore water; equal in all "
                     "materials [Pa]")
    # k = 0: the no-flow limit, p follows the volumetric strain (Eq. 25 without its Darcy
    # term), the counterpart of the penalty-based undrained models
    k: Annotated[float, Field(ge=0.0)] = Field(
        description="Hydraulic conductivity at the initial void ratio; 0: no flow [m/s]")
    g_ref: Pos = Field(9.81, description="Gravity that converts k to a permeability, gamma_l "
                       "= rho_l g_ref; equal in all materials [m/s^2]")
    C_k: Annotated[float, Field(ge=0.0)] = Field(
        0.0, description="Kozeny-Carman coefficient of Eq. (4), k = k0 exp((e − e0)/C_k); 0 "
        "keeps k constant [-]")
    # the densest state of the soil
    porosity_min: Annotated[float, Field(ge=0.0, lt=1.0)] = Field(
        0.0, description="Floor of the porosity of Eq. (24); 0 is no floor [-]")


class NamedMaterial(Material):
    """One of several materials (`[[materials]]`): a `name` the particle sources use."""

    name: Annotated[str, Field(min_length=1)] = Field(
        description="Name that the particle sources use in `material = \"...\"`; unique")


def check_material(m: Material, key: str) -> None:
    """The rules between one material's keys (`key`: "material" or "materials[i]")."""
    if not m.porosity_min < m.porosity:
        raise _Rule(f"{key}.porosity", m.porosity,
                    f"must be above {key}.porosity_min = {m.porosity_min}")
    if m.model == "drucker_prager" and m.plasticity is None:
        raise _Rule(f"{key}.plasticity", None,
                    f"required for {key}.model = 'drucker_prager' (at least phi)")
    if m.model == "elastic" and m.plasticity is not None:
        raise _Rule(f"{key}.model", "elastic",
                    f"{key}.plasticity is given: set model = 'drucker_prager'")


def check_materials(scene) -> list[Material]:
    """Exactly one of `[material]` and `[[materials]]`, unique names, one pore fluid
    (`FLUID_KEYS` equal), each material's own rules, and every particle source's
    `material` an existing name. Returns the materials in index order (index 0: the one
    `[material]`, or the first of `[[materials]]`, which sources without `material` take)."""
    if scene.material is not None and scene.materials:
        raise _Rule("materials", f"{len(scene.materials)} tables",
                    "give either one [material] table or [[materials]] tables, not both")
    if scene.material is None and not scene.materials:
        raise _Rule("material", None, "required: give a [material] table or [[materials]] "
                    "tables")
    if scene.material is not None:
        check_material(scene.material, "material")
        mats, names = [scene.material], {}
    else:
        mats, names = list(scene.materials), {}
        for i, m in enumerate(mats):
            key = f"materials[{i}]"
            if m.name in names:
                raise _Rule(f"{key}.name", m.name,
                            f"duplicate name (also materials[{names[m.name]}].name)")
            names[m.name] = i
            check_material(m, key)
            for fk in FLUID_KEYS:
                if getattr(m, fk) != getattr(mats[0], fk):
                    raise _Rule(f"{key}.{fk}", getattr(m, fk),
                                f"the pore fluid is one fluid: must equal materials[0].{fk} "
                                f"= {getattr(mats[0], fk)!r}")
    pa = scene.particles
    for kind in ("blocks", "polygons", "meshes", "layers", "spheres", "cylinders"):
        for i, src in enumerate(getattr(pa, kind)):
            if src.material is not None and src.material not in names:
                known = ", ".join(repr(n) for n in names) or "none: [material] has no name"
                raise _Rule(f"particles.{kind}[{i}].material", src.material,
                            f"no such material (names: {known})")
    return mats

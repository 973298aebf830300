"""The soil materials of a scene (Section 2.2): one `[material]` table, or several
`[[materials]]` tables by name that the particle sources pick with `material = "name"`
(issue 16). Validation raises `_Rule` (key, value, rule), which `psph.config.load.validate`
turns into one line and exit 2."""

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from psph.errors import SceneRule as _Rule

Pos = Annotated[float, Field(gt=0)]

# the pore fluid is one fluid: these keys must agree across the materials
FLUID_KEYS = ("rho_l", "K_l", "g_ref")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, validate_default=True)


class Regularisation(_Model):
    """Regularised (mesh-objective) softening (issue 17): Eq. (17)-(19) driven by the
    over-non-local equivalent plastic strain eps_hat = (1 - m) eps_p + m eps_bar, eps_bar
    the average of eps_p with the cubic spline of smoothing length `length` (support
    2 length; psph/kernels/nonlocal_strain.py). `length` is the internal length l_c in
    metres, a material property independent of dx; m = 1: the plain average."""

    kind: Literal["nonlocal"]
    length: Annotated[float, Field(gt=0.0)]  # l_c (m)
    m: Annotated[float, Field(ge=1.0)] = 2.0  # over-non-local weight


class Plasticity(_Model):
    """Drucker-Prager strain softening, Eq. (14)-(19). Angles in degrees, cohesion in Pa;
    residual values default to the peak ones (no softening)."""

    phi: Annotated[float, Field(ge=0.0, lt=90.0)]  # peak friction angle phi_p
    phi_r: Annotated[float, Field(ge=0.0, lt=90.0)] | None = None  # residual, Eq. (17)
    c: Annotated[float, Field(ge=0.0)] = 0.0  # peak cohesion c_p
    c_r: Annotated[float, Field(ge=0.0)] | None = None  # residual, Eq. (18)
    psi: Annotated[float, Field(gt=-90.0, lt=90.0)] = 0.0  # initial dilation psi_0, Eq. (19)
    eta: Annotated[float, Field(ge=0.0)] = 0.0  # softening rate of phi and c, Eq. (17)-(18)
    s_f: Annotated[float, Field(ge=0.0)] = 0.0  # decay rate of dilation, Eq. (19)
    regularisation: Regularisation | None = None  # None: the local law
    # tension cut-off: the largest mean effective stress sigma'_m (Pa, tension positive)
    # the soil carries (issue 13); None: the apex c cot(phi) of Eq. (14), the paper's law
    tension_cutoff: Annotated[float, Field(ge=0.0)] | None = None


class Material(_Model):
    """Saturated soil, linear elastic or elastic-plastic (Section 2.2; units Pa, kg/m^3,
    m/s)."""

    model: Literal["elastic", "drucker_prager"] = "elastic"
    plasticity: Plasticity | None = None  # required for model = "drucker_prager"
    E: Pos
    nu: Annotated[float, Field(gt=-1.0, lt=0.5)]
    porosity: Annotated[float, Field(gt=0.0, lt=1.0)]
    rho_s: Pos
    rho_l: Pos = 1000.0
    K_l: Pos = 1.0e9
    k: Pos
    g_ref: Pos = 9.81  # converts hydraulic conductivity k: gamma_l = rho_l g_ref
    # Kozeny-Carman coefficient of Eq. (4), k = k exp((e - e0) / C_k); 0: constant k
    C_k: Annotated[float, Field(ge=0.0)] = 0.0
    # floor of the porosity of Eq. (24) (the densest state of the soil); 0: none
    porosity_min: Annotated[float, Field(ge=0.0, lt=1.0)] = 0.0


class NamedMaterial(Material):
    """One of several materials (`[[materials]]`): a `name` the particle sources use."""

    name: Annotated[str, Field(min_length=1)]


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
    for kind in ("blocks", "polygons", "meshes", "layers"):
        for i, src in enumerate(getattr(pa, kind)):
            if src.material is not None and src.material not in names:
                known = ", ".join(repr(n) for n in names) or "none: [material] has no name"
                raise _Rule(f"particles.{kind}[{i}].material", src.material,
                            f"no such material (names: {known})")
    return mats

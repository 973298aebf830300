"""Loading a scene: a built-in name (psph/scenes/*.toml) or a TOML file -> validated,
fully resolved `Scene`.

Layers: model defaults < scene file < `--set key.path=value`. Unknown keys, wrong types and
out-of-range values raise `SceneError` with one line naming the key, the value and the rule.
"""

import tomllib
from pathlib import Path

import tomli_w
from pydantic import ValidationError

from psph.config.schema import Scene
from psph.errors import SceneError
from psph.errors import SceneRule as _Rule
from psph.verify import reference_times


def run_scene(out: Path) -> Scene:
    """The validated scene a run wrote to OUT/scene.toml (OSError, SceneError)."""
    path = Path(out) / "scene.toml"
    return validate(tomllib.loads(path.read_text()), str(path))


def builtin_dir() -> Path:
    return Path(__file__).parent.parent / "scenes"


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
    find_data_files(data, Path(label).parent)
    scene = validate(data, label)
    return resolve(scene)


def _file_keys(data: dict):
    """(table, key) of every value of a scene that may name a data file: meshes,
    profiles and grids of layers, polylines' points, surfaces' meshes and grids, a water
    table."""
    pa = data.get("particles", {})
    for mesh in pa.get("meshes", []) if isinstance(pa, dict) else []:
        yield mesh, "file"
    for layer in pa.get("layers", []) if isinstance(pa, dict) else []:
        yield layer, "top"
        yield layer, "bottom"
    b = data.get("boundaries", {})
    for line in b.get("polylines", []) if isinstance(b, dict) else []:
        yield line, "points"
    for surface in b.get("surfaces", []) if isinstance(b, dict) else []:
        yield surface, "mesh"
        yield surface, "grid"
    yield data.get("initial", {}), "water_table"


def find_data_files(data: dict, scene_dir: Path) -> None:
    """A relative data file (`_file_keys`) that is not found from the working directory
    but is beside the scene file is named by its absolute path there: a scene and its
    grids, profiles and meshes can be run from anywhere, and a built-in scene can ship
    its data in psph/scenes. Found from the working directory, a path stays as it is."""
    for table, key in _file_keys(data):
        if not isinstance(table, dict):
            continue
        value = table.get(key)
        if not isinstance(value, str) or value == "surface" or Path(value).is_absolute():
            continue
        if not Path(value).exists() and (scene_dir / value).is_file():
            table[key] = str((scene_dir / value).resolve())


def resolve(scene: Scene) -> Scene:
    """Fill values derived from others (end time from the verification times, artificial
    stress from the material model)."""
    if scene.stabilisation.artificial_stress is None:
        scene = scene.model_copy(deep=True)
        scene.stabilisation.artificial_stress = \
            0.5 if any(m.model == "drucker_prager" for m in scene.material_list) else 0.0
    if scene.time.end is None:
        t = reference_times(scene)
        scene = scene.model_copy(deep=True)
        scene.time.end = float(max(t))
    return scene


def to_toml(scene: Scene) -> str:
    return tomli_w.dumps(scene.model_dump(exclude_none=True))


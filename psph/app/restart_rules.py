"""The restart rule: a restart continues the same physics (docs/guide/restart_clusters.md).
Only scheduling sections may differ from the scene stored in the checkpoint."""

import tomllib

from psph.config.load import resolve, validate
from psph.config.schema import Scene
from psph.errors import SceneError

# Sections a restart may change: they schedule the run, they do not change its physics.
RESTART_MUTABLE = ("description", "time.end", "output", "checkpoint", "decomposition")
# Keys that only check the input (`boundaries.<side>.symmetry`, checked on the seeded
# particles of a fresh run): a checkpoint written before they were set continues.
CHECK_ONLY = ("symmetry",)


def check_restart_scene(saved_toml: str, scene: Scene, label: str) -> None:
    """A restart continues the same physics: every key outside RESTART_MUTABLE must equal
    the checkpoint's. Raises SceneError naming the first key that differs."""
    diff = physics_difference(saved_toml, scene, label)
    if diff is not None:
        key, now, saved = diff
        raise SceneError(
            f"{label}: {key} = {now!r} differs from the checkpoint's {saved!r}; rule: a "
            f"restart may only change {', '.join(RESTART_MUTABLE)}")


def physics_difference(saved_toml: str, scene: Scene, label: str
                       ) -> tuple[str, object, object] | None:
    """The first key outside RESTART_MUTABLE where `scene` differs from the scene
    `saved_toml` (key, scene's value, saved value), or None. The saved scene is validated
    first (SceneError naming `label` if it is not valid), so a key added since it was
    written (whose default keeps the old behaviour) compares as its default."""
    saved = _flatten(resolve(validate(tomllib.loads(saved_toml), label))
                     .model_dump(exclude_none=True))
    now = _flatten(scene.model_dump(exclude_none=True))
    for key in sorted(set(saved) | set(now)):
        if any(key == m or key.startswith(m + ".") for m in RESTART_MUTABLE):
            continue
        if key.startswith("boundaries.") and key.rsplit(".", 1)[-1] in CHECK_ONLY:
            continue
        if saved.get(key) != now.get(key):
            return key, now.get(key), saved.get(key)
    return None


def _flatten(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flatten(v, key + "."))
        else:
            out[key] = v
    return out

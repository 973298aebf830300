"""The restart rule: a restart continues the same physics (DESIGN.md, checkpoint/restart).
Only scheduling sections may differ from the scene stored in the checkpoint."""

import tomllib

from psph.errors import SceneError
from psph.scene import Scene, resolve, validate

# Sections a restart may change: they schedule the run, they do not change its physics.
RESTART_MUTABLE = ("description", "time.end", "output", "checkpoint", "decomposition")


def check_restart_scene(saved_toml: str, scene: Scene, label: str) -> None:
    """A restart continues the same physics: every key outside RESTART_MUTABLE must equal
    the checkpoint's. Raises SceneError naming the first key that differs. The saved scene
    is validated first, so a key added since the checkpoint was written (whose default
    keeps the old behaviour) compares as its default."""
    saved = _flatten(resolve(validate(tomllib.loads(saved_toml), label))
                     .model_dump(exclude_none=True))
    now = _flatten(scene.model_dump(exclude_none=True))
    for key in sorted(set(saved) | set(now)):
        if any(key == m or key.startswith(m + ".") for m in RESTART_MUTABLE):
            continue
        if saved.get(key) != now.get(key):
            raise SceneError(
                f"{label}: {key} = {now.get(key)!r} differs from the checkpoint's "
                f"{saved.get(key)!r}; rule: a restart may only change "
                f"{', '.join(RESTART_MUTABLE)}")


def _flatten(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flatten(v, key + "."))
        else:
            out[key] = v
    return out

"""Branch a run at a checkpoint: copy `checkpoint.h5` with scene overrides written into it,
so that `psph run --restart COPY --set ...` continues the same state under other physics
(an experiment from the middle of a run; a plain restart refuses any change of physics).

    python -m psph.io.branch OUT/checkpoint.h5 BRANCH.h5 --set stabilisation.shepard_every=0
    mpirun -n 2 .venv/bin/python -m psph run SCENE --restart BRANCH.h5 \\
        --set stabilisation.shepard_every=0 --out OUT2

The copy is a different run: its physics changed at the checkpoint's time. Overrides of
the set-up (particle spacing, geometry) are accepted but meaningless: the state is the
checkpoint's.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

import h5py

from psph.config.load import load_scene, to_toml
from psph.errors import SceneError
from psph.io.checkpoint import read_checkpoint


def branch_checkpoint(src: Path, dst: Path, overrides: list[str]) -> None:
    """Copy `src` to `dst` and replace its stored scene by the scene with `overrides`
    (validated as any scene; SceneError on a bad one)."""
    with h5py.File(src, "r") as f:
        meta = json.loads(f.attrs["meta"])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.toml"
        path.write_text(meta["scene"])
        meta["scene"] = to_toml(load_scene(str(path), overrides))
    shutil.copyfile(src, dst)
    with h5py.File(dst, "r+") as f:
        f.attrs["meta"] = json.dumps(meta)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m psph.io.branch",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("checkpoint", type=Path)
    ap.add_argument("branch", type=Path)
    ap.add_argument("--set", action="append", default=[], help="key.path=value")
    args = ap.parse_args(argv)
    try:
        read_checkpoint(args.checkpoint)  # a complete psph checkpoint, or one clear line
        if args.branch.resolve() == args.checkpoint.resolve():
            raise SceneError(f"{args.branch}: the branch must be a new file, not the "
                             "checkpoint itself")
        branch_checkpoint(args.checkpoint, args.branch, args.set)
    except OSError as e:
        print(f"psph: error: {args.branch}: {e.strerror or e}", file=sys.stderr)
        return 2
    except SceneError as e:
        print(f"psph: error: {e}", file=sys.stderr)
        return 2
    print(f"wrote {args.branch}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Write the elevation grids of the built-in `slope_3d` scene into psph/scenes:

- `slope_3d_ground.asc`: a synthetic valley side, the Section 4.5 profile (a 20 m high
  clay slope at 27 degrees, crest at x = 140.749 m, toe at x = 180 m, the polygon of
  `retrogressive_k0_0.5`) extruded across the valley, y = 0..30 m (the half of a 60 m
  valley on one side of its centre line, y = 0), flat at z = 0 beyond the toe to
  x = 1000 m (the river's floodplain); nodes every metre;
- `slope_3d_base.asc`: the flat bedrock z = 0 under it (its four corners).

The river's cut of the toe is the scene's `[[remove]]` polygon, not the grid.

    python bench/tools/slope_3d_grids.py                  # into psph/scenes (seconds)
    python bench/tools/slope_3d_grids.py --out DIR        # elsewhere, to compare
"""

import argparse
from pathlib import Path

import numpy as np

SCENES = Path(__file__).resolve().parents[2] / "psph" / "scenes"
CREST, TOE, HEIGHT = 140.749, 180.0, 20.0  # retrogressive_k0_0.5's polygon
LENGTH, HALF_WIDTH, CELL = 1000.0, 30.0, 1.0


def ground(x: np.ndarray) -> np.ndarray:
    """The slope's profile z(x): the crest's level, the 27 degree face, the floor."""
    return np.clip(HEIGHT * (TOE - x) / (TOE - CREST), 0.0, HEIGHT)


def write_asc(path: Path, z: np.ndarray, dx: float, dy: float) -> None:
    """z (ny, nx) on nodes from (0, 0) every dx and dy, row 0 the southern (y = 0); the
    file has the northern row first, as the format wants."""
    ny, nx = z.shape
    size = [f"cellsize {dx}"] if dx == dy else [f"dx {dx}", f"dy {dy}"]
    head = [f"ncols {nx}", f"nrows {ny}", "xllcenter 0.0", "yllcenter 0.0"] + size
    rows = [" ".join(f"{v:.4f}".rstrip("0").rstrip(".") for v in z[j])
            for j in range(ny - 1, -1, -1)]
    path.write_text("\n".join(head + rows) + "\n")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=SCENES,
                    help="directory of the two .asc files (default psph/scenes)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    x = np.arange(0.0, LENGTH + CELL / 2, CELL)
    y = np.arange(0.0, HALF_WIDTH + CELL / 2, CELL)
    write_asc(args.out / "slope_3d_ground.asc", np.tile(ground(x), (len(y), 1)), CELL, CELL)
    write_asc(args.out / "slope_3d_base.asc", np.zeros((2, 2)), LENGTH, HALF_WIDTH)
    print(f"wrote {args.out / 'slope_3d_ground.asc'} and slope_3d_base.asc "
          f"({len(x)} x {len(y)} nodes)")


if __name__ == "__main__":
    main()

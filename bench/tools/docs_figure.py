"""Copy a bench or `psph plot` picture into docs/ at the README's width.

    python bench/tools/docs_figure.py SRC DST [--width 1000]

The README's pictures are these copies (e.g. `bench/out/convergence-slope.png` ->
`docs/convergence_slope.png`): resized with Lanczos to `--width` pixels, the aspect
ratio kept; a narrower source is copied as it is.
"""

import argparse
import sys
from pathlib import Path

from PIL import Image


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src", type=Path)
    ap.add_argument("dst", type=Path)
    ap.add_argument("--width", type=int, default=1000)
    args = ap.parse_args(argv)
    image = Image.open(args.src)
    if image.width > args.width:
        height = round(image.height * args.width / image.width)
        image = image.resize((args.width, height), Image.Resampling.LANCZOS)
    image.save(args.dst)
    print(f"wrote {args.dst} ({image.width} x {image.height})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

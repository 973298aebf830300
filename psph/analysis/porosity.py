"""`python -m psph.analysis.porosity OUT [OUT ...]`: the porosity of Drucker-Prager runs
against the flow rule's own bound (`psph.verify.porosity`), for every snapshot at a
multiple of `--every` seconds.
"""

import argparse
import sys
from pathlib import Path

from psph.config.load import run_scene
from psph.errors import SceneError
from psph.io.snapshots import read_snapshots
from psph.verify.porosity import DEFICIT, porosity_deficit


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m psph.analysis.porosity",
                                 description="porosity against the flow rule's bound")
    ap.add_argument("out", nargs="+", type=Path, help="run output directories")
    ap.add_argument("--every", type=float, default=5.0, help="snapshot spacing to print (s)")
    args = ap.parse_args(argv)
    status = 0
    for out in args.out:
        try:
            scene = run_scene(out)
            snaps = read_snapshots(out / "particles.h5")
        except (OSError, SceneError) as e:
            print(f"{out}: error: {e}", file=sys.stderr)
            status = 2
            continue
        pl = scene.material.plasticity
        if pl is None:
            print(f"{out}: not a Drucker-Prager run", file=sys.stderr)
            status = 2
            continue
        print(f"{out}  (n0 = {scene.material.porosity}, psi0 = {pl.psi} deg, s_f = {pl.s_f})")
        for snap in snaps:
            k = snap["time"] / args.every
            if abs(k - round(k)) > 1e-6:
                continue
            d = porosity_deficit(snap, scene.material.porosity, pl.psi, pl.s_f)
            print(f"  t = {d['time_s']:5.1f} s  n_min {d['n_min']:.3f}  largest n_law - n "
                  f"{d['deficit_max']:+.3f} (id {d['deficit_id']}, eps_p "
                  f"{d['deficit_eps_p']:.2f}, n {d['deficit_n']:.3f})  more than "
                  f"{DEFICIT} below: {d['below_bound']}")
    return status


if __name__ == "__main__":
    sys.exit(main())

"""`python -m psph.analysis.particle OUT ID [--from T0] [--to T1]`: one particle's pore
pressure against its neighbours and the terms of Eq. (26) that hold it there, one row per
snapshot (`psph.verify.particle.particle_terms`); with `--bands` instead of ID, p against
the neighbours' by height band above the floor (`psph.verify.particle.basal_bands`).
"""

import argparse
import sys
from pathlib import Path

import numpy as np

from psph.config.load import run_scene
from psph.errors import SceneError
from psph.io.snapshots import read_snapshots
from psph.verify.particle import basal_bands, particle_terms


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m psph.analysis.particle",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("id", type=int, nargs="?", help="the particle to follow")
    ap.add_argument("--bands", action="store_true", help="p against the neighbours' by "
                    "height band above the floor, every snapshot")
    ap.add_argument("--from", dest="t0", type=float, default=0.0)
    ap.add_argument("--to", dest="t1", type=float, default=np.inf)
    args = ap.parse_args(argv)
    try:
        scene = run_scene(args.out)
        snaps = read_snapshots(args.out / "particles.h5")
    except SceneError as e:
        print(f"psph: error: {e}", file=sys.stderr)
        return 2
    snaps = [s for s in snaps if args.t0 - 1e-9 <= s["time"] <= args.t1 + 1e-9]
    if args.bands:
        for s in snaps:
            print(f"t = {s['time']:.3g} s: height above the floor (dx), particles, and p - "
                  "neighbours' mean p: median / p99 / max (kPa)")
            for b in basal_bands(s, scene):
                if b["particles"]:
                    print(f"  {b['band_dx'][0]:5.3f}-{b['band_dx'][1]:5.3f} "
                          f"{b['particles']:6d}  {b['median_Pa'] / 1e3:7.1f} "
                          f"{b['p99_Pa'] / 1e3:7.1f} {b['max_Pa'] / 1e3:7.1f}")
        return 0
    if args.id is None:
        ap.error("give a particle id, or --bands")
    print(f"{'t (s)':>7s} {'y (m)':>6s} {'p':>7s} {'p nb':>7s} {'n':>6s} {'sum VW':>6s} "
          f"{'own p acc y':>11s} {'nb p acc y':>10s} {'div plain':>9s} {'div corr':>9s}"
          "   (kPa, m/s^2, 1/s)")
    for s in snaps:
        if args.id not in s["id"]:
            continue
        t = particle_terms(s, args.id, scene)
        print(f"{t['time_s']:7.3f} {t['y']:6.3f} {t['p'] / 1e3:7.1f} "
              f"{t['p_neighbours'] / 1e3:7.1f} {t['n']:6.3f} {t['kernel_sum']:6.3f} "
              f"{t['acc_own_p'][1]:11.2f} {t['acc_neighbours_p'][1]:10.2f} "
              f"{t['div_v_plain']:9.3f} {t['div_v_corrected']:9.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

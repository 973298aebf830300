"""`python -m psph.analysis.pressure OUT [OUT ...] [--write]`: the pressure quality of
psph runs (`psph.verify.pressure`) from their snapshots, one line per run; with `--write`
the block is stored as `metrics.pressure_quality` in each OUT/summary.json. `--where` and
`--row` say where the largest excess sits and print p along a row of particles.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from psph.config.load import run_scene
from psph.errors import SceneError
from psph.io.snapshots import read_snapshots
from psph.verify.pressure import (
    PHREATIC_ROWS,
    excess_pressure,
    hydrostatic_pressure,
    phreatic_excess,
    pressure_quality,
    wet_threshold,
)


def _fmt(v, scale: float = 1.0, spec: str = ".1f") -> str:
    return "-" if v is None else format(v / scale, spec)


def _where_largest(snap: dict, scene) -> str:
    """One line: sign, extent and share near the floor of the particles in the top 1 % of
    |excess p| of a snapshot, the 99th percentile of |excess| within 1.5 dx of the
    domain's floor (the bottom row, at 0.5 dx, and particles sunk below the second row's
    1.5 dx) and above it, and the share of those particles whose |p| is below the
    hydrostatic pressure of PHREATIC_ROWS rows (drained rather than in suction) with
    their median p."""
    ex = excess_pressure(snap, scene)
    a = np.abs(ex)
    top = a >= np.percentile(a, 99)
    x, y = snap["x"][:, 0], snap["x"][:, 1]
    base = y - scene.domain.min[1] < 1.5 * scene.particles.dx
    drained = np.abs(snap["p"][top]) < wet_threshold(scene)
    return (f"t = {snap['time']:.3g} s, top 1 % of |excess| ({int(top.sum())} particles): "
            f"{int((ex[top] > 0).sum())} positive, {int((ex[top] < 0).sum())} negative; "
            f"x {x[top].min():.2f}..{x[top].max():.2f} m, y {y[top].min():.2f}..{y[top].max():.2f}"
            f" m; {100 * base[top].mean():.0f} % within 1.5 dx of the floor; p99 of |excess| "
            f"there {_p99_kpa(a[base])}, above {_p99_kpa(a[~base])}; "
            f"{100 * drained.mean():.0f} % with |p| below the hydrostatic of "
            f"{PHREATIC_ROWS:g} rows (drained, not suction), median p "
            f"{np.median(snap['p'][top]) / 1e3:.1f} kPa")


def _row_profile(snap: dict, scene, y: float, every: int) -> str:
    """Lines of x, p, the surface table's hydrostatic p and the excess over the phreatic
    line along the particles within dx/2 of elevation y (every `every`-th from the
    right end, where a collapse's face is)."""
    x = snap["x"]
    row = np.flatnonzero(np.abs(x[:, 1] - y) < 0.5 * scene.particles.dx)
    row = row[np.argsort(-x[row, 0])][::every]
    hydro = hydrostatic_pressure(x, scene)
    phreatic = phreatic_excess(snap, scene)
    lines = [f"  t = {snap['time']:.3g} s, y = {y:g} m: x (m), p, hydrostatic (surface), "
             "excess over the phreatic line (kPa)"]
    lines += [f"    {x[i, 0]:8.3f} {snap['p'][i] / 1e3:8.2f} {hydro[i] / 1e3:8.2f} "
              f"{phreatic[i] / 1e3:8.2f}" for i in row]
    return "\n".join(lines)


def _p99_kpa(a: np.ndarray) -> str:
    return f"{np.percentile(a, 99) / 1e3:.1f} kPa" if len(a) else "- (none)"


def main(argv: list[str] | None = None) -> int:
    """`python -m psph.analysis.pressure OUT [OUT ...] [--write]`: one line per run."""
    ap = argparse.ArgumentParser(prog="python -m psph.analysis.pressure",
                                 description="pressure quality of psph runs (excess pore "
                                 "pressure, checkerboard index of p and p')")
    ap.add_argument("out", nargs="+", type=Path, help="run output directories")
    ap.add_argument("--write", action="store_true",
                    help="add/replace metrics.pressure_quality in OUT/summary.json")
    ap.add_argument("--at", type=float, default=None,
                    help="use the snapshots up to this time (s) only (compare runs of "
                    "different lengths at one time)")
    ap.add_argument("--where", action="store_true",
                    help="also say where the top 1 %% of |excess| sits at the last snapshot "
                    "used: its sign, extent, how much of it is within 1.5 dx of the "
                    "floor, and how much of it is drained (|p| near 0) rather than suction")
    ap.add_argument("--row", type=float, default=None, metavar="Y",
                    help="also print p along the particles at elevation Y (m) at the last "
                    "snapshot used, from the right end, against the hydrostatic pressure")
    ap.add_argument("--every", type=int, default=5, help="with --row: every N-th particle")
    args = ap.parse_args(argv)
    print(f"{'run':<32} {'t_end':>6} {'min_ex':>9} {'max_ex':>9} {'p1_ex':>9} {'p99_ex':>9}"
          f" {'abs_p99':>9} {'cb_p_deb':>8} {'cb_pe_deb':>9} {'phr_p99':>9} {'suct_p99':>9}"
          "   (excess p in kPa: min, max, lowest p1, highest p99 and highest 99th percentile "
          "of |excess| over the snapshots; checkerboard of p and p' in the debris at the "
          "last snapshot; highest 99th percentiles of |excess over the phreatic line| and "
          "of the suction max(-p, 0), kPa)")
    status = 0
    for out in args.out:
        try:
            scene = run_scene(out)
            snaps = read_snapshots(out / "particles.h5")
            if args.at is not None:
                snaps = [sn for sn in snaps if sn["time"] <= args.at * (1 + 1e-9)]
        except (OSError, SceneError) as e:
            print(f"{str(out):<32} error: {e}", file=sys.stderr)
            status = 2
            continue
        q = pressure_quality(snaps, scene)
        o = q["over_run"]
        print(f"{out.name or str(out):<32} {q['series']['time_s'][-1]:>6.3g} "
              f"{_fmt(o['excess_min_Pa'], 1e3):>9} {_fmt(o['excess_max_Pa'], 1e3):>9} "
              f"{_fmt(o['excess_p1_min_Pa'], 1e3):>9} {_fmt(o['excess_p99_max_Pa'], 1e3):>9} "
              f"{_fmt(o['abs_excess_p99_max_Pa'], 1e3):>9} "
              f"{_fmt(o['checkerboard_p_debris_last'], 1, '.3f'):>8} "
              f"{_fmt(o['checkerboard_p_eff_debris_last'], 1, '.3f'):>9} "
              f"{_fmt(o['abs_phreatic_excess_p99_max_Pa'], 1e3):>9} "
              f"{_fmt(o['suction_p99_max_Pa'], 1e3):>9}")
        if args.where:
            print("  " + _where_largest(snaps[-1], scene))
        if args.row is not None:
            print(_row_profile(snaps[-1], scene, args.row, max(args.every, 1)))
        if args.write and args.at is None:
            path = out / "summary.json"
            summary = json.loads(path.read_text()) if path.is_file() else {}
            summary.setdefault("metrics", {})["pressure_quality"] = q
            path.write_text(json.dumps(summary, indent=2) + "\n")
    return status


if __name__ == "__main__":
    sys.exit(main())

"""The excess pore pressure of collapse snapshots over the two references of
psph/verify/pressure.py, side by side: over the ground surface's table
(`excess_pressure`, what `psph plot` draws) and over the current phreatic line
(`phreatic_excess`), with the pore pressure itself (issue 13, the psi = 0 line).

    python bench/diagnostics/phreatic_picture.py runs/collapse_saturated_psi0 \
        runs/collapse_saturated_psi2.5 --at 0.6 --png bench/out/phreatic.png

One row per run: p, excess over the surface, excess over the phreatic line (kPa, one
colour scale per row, symmetric about 0), at the snapshot nearest --at. Writes the PNG
and bench/out/phreatic_picture.json (each panel's 1st and 99th percentiles).
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from psph.config.load import run_scene
from psph.io.snapshots import read_snapshots
from psph.verify.pressure import excess_pressure, phreatic_excess

ROOT = Path(__file__).resolve().parents[2]


def panels(run: Path, at: float) -> tuple[dict, dict]:
    """The snapshot nearest `at` and its three fields (Pa)."""
    scene = run_scene(run)
    snap = min(read_snapshots(run / "particles.h5"), key=lambda s: abs(s["time"] - at))
    return snap, {"p": snap["p"], "excess over the surface": excess_pressure(snap, scene),
                  "excess over the phreatic line": phreatic_excess(snap, scene)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--at", type=float, default=0.6, help="time (s)")
    ap.add_argument("--png", type=Path, default=ROOT / "bench" / "out" / "phreatic.png")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(args.runs), 3, figsize=(15, 2.6 * len(args.runs) + 0.6),
                             squeeze=False, layout="constrained")
    report = {}
    for row, run in zip(axes, args.runs, strict=True):
        snap, fields = panels(run, args.at)
        limit = max(np.percentile(np.abs(f), 99.5) for f in fields.values()) / 1e3 or 1.0
        report[run.name] = {"time_s": float(snap["time"])}
        for ax, (name, f) in zip(row, fields.items(), strict=True):
            sc = ax.scatter(snap["x"][:, 0], snap["x"][:, 1], c=f / 1e3, s=1.5,
                            cmap="RdBu_r", vmin=-limit, vmax=limit, rasterized=True)
            p1, p99 = np.percentile(f, [1, 99]) / 1e3
            report[run.name][name] = {"p1_kPa": float(p1), "p99_kPa": float(p99)}
            ax.set_title(f"{run.name}, t = {snap['time']:.2f} s: {name}\n"
                         f"1st / 99th percentile {p1:.1f} / {p99:.1f} kPa", fontsize=8)
            ax.set_aspect("equal")
            ax.set_xlim(0.0, float(snap["x"][:, 0].max()) + 0.2)
        fig.colorbar(sc, ax=row, label="kPa", shrink=0.9)
    fig.savefig(args.png, dpi=110)
    out = ROOT / "bench" / "out"
    out.mkdir(exist_ok=True)
    (out / "phreatic_picture.json").write_text(json.dumps(report, indent=1) + "\n")
    for name, r in report.items():
        print(name, json.dumps(r))
    print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

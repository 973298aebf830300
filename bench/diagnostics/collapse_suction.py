"""Where a saturated collapse's suction comes from (issue 13, the psi = 0 line): at each
snapshot, the particles whose pore pressure is below -gamma_l 2 dx (the threshold of
`psph.verify.pressure.PHREATIC_ROWS`), with their median p, mean effective stress p'
(compression positive), sqrt(J2) of the effective stress, porosity, eps_p and height, and
the share of them at the Drucker-Prager apex (sqrt(J2) below 1 % of the peak cohesion c):
there the return is a volumetric one whatever psi is (Eq. 14-16), so a psi = 0 soil
stretched at its free surface expands plastically and its undrained pore water answers
with suction ("the soil above the phreatic line subsequently underwent volumetric
dilation, and thus negative pore-water pressure", the paper on Fig. 16).

    python bench/diagnostics/collapse_suction.py runs/collapse_saturated_psi0 [RUN ...]

Prints a table per run and writes bench/out/collapse_suction.json.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from psph.config.load import run_scene
from psph.io.snapshots import read_snapshots
from psph.verify.element import sqrt_j2
from psph.verify.pressure import PHREATIC_ROWS, mean_effective_stress, wet_threshold

ROOT = Path(__file__).resolve().parents[2]


def suction_rows(run: Path) -> list[dict]:
    """One row per snapshot after t = 0 (see the module docstring)."""
    scene = run_scene(run)
    threshold = -wet_threshold(scene)
    apex_j2 = 0.01 * scene.material.plasticity.c
    n0 = scene.material.porosity
    rows = []
    for s in read_snapshots(run / "particles.h5")[1:]:
        suck = s["p"] < threshold
        row = {"time_s": float(s["time"]), "particles": int(suck.sum())}
        if suck.any():
            j2 = sqrt_j2(s["stress"][suck])
            row.update(p_kPa=float(np.median(s["p"][suck])) / 1e3,
                       p_eff_kPa=float(np.median(mean_effective_stress(s["stress"][suck]))) / 1e3,
                       root_j2_kPa=float(np.median(j2)) / 1e3, at_apex=float(np.mean(j2 < apex_j2)),
                       n=float(np.median(s["n"][suck])),
                       expanded=float(np.mean(s["n"][suck] > n0 + 0.005)),
                       eps_p=float(np.median(s["eps_p"][suck])),
                       y_m=float(np.median(s["x"][suck, 1])))
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="collapse output directories")
    args = ap.parse_args(argv)
    report = {}
    for run in args.runs:
        report[run.name] = rows = suction_rows(run)
        print(f"{run.name}: particles with p < -gamma_l {PHREATIC_ROWS:g} dx (medians)")
        print(f"{'t (s)':>6s} {'count':>6s} {'p kPa':>7s} {'p_eff':>7s} {'sqrtJ2':>7s} "
              f"{'apex':>5s} {'n':>7s} {'n>n0':>5s} {'eps_p':>6s} {'y m':>5s}")
        for r in rows:
            if r["particles"] == 0:
                print(f"{r['time_s']:6.2f} {0:6d}")
                continue
            print(f"{r['time_s']:6.2f} {r['particles']:6d} {r['p_kPa']:7.2f} "
                  f"{r['p_eff_kPa']:7.2f} {r['root_j2_kPa']:7.2f} {r['at_apex']:5.0%} "
                  f"{r['n']:7.4f} {r['expanded']:5.0%} {r['eps_p']:6.2f} {r['y_m']:5.2f}")
    out = ROOT / "bench" / "out"
    out.mkdir(exist_ok=True)
    (out / "collapse_suction.json").write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

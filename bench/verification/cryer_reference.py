"""Cryer's sphere, the reference of the 3D scene `cryer`, checked before any 3D
run: the centre pressure of the analytical series (`psph/verify/cryer.py`, Verruijt
Sect. 3.3) against the radial finite-volume solution of the same equations
(`radial_centre_pressure`) at two grids, for three soils: the peak of the Mandel-Cryer
rise, its time, and the largest difference over tau = c t / a^2 in [0.005, 1].

    .venv/bin/python bench/verification/cryer_reference.py            # ~10 s
    .venv/bin/python bench/verification/cryer_reference.py --quick    # the first soil

Prints a table, writes <out>/cryer_reference.json and .png (p / p0 at the centre
against tau, series and radial solution).
"""

import argparse
import json
import platform
from datetime import date
from pathlib import Path

import numpy as np

from psph.verify.cryer import Cryer, radial_centre_pressure

OUT = Path(__file__).resolve().parents[1] / "out"
SOILS = {  # (nu, K_l): the paper's column's soil, a soil with nu = 0, a softer pore fluid
    "nu = 0.25, K_l = 1 GPa": (0.25, 1.0e9),
    "nu = 0, K_l = 1 GPa": (0.0, 1.0e9),
    "nu = 0.3, K_l = 20 MPa": (0.3, 2.0e7),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="the first soil alone")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of cryer_reference.json and .png (default bench/out)")
    args = ap.parse_args()
    soils = dict(list(SOILS.items())[:1]) if args.quick else SOILS
    taus = np.round(np.concatenate([np.arange(0.005, 0.2, 0.005),
                                    np.arange(0.2, 1.0001, 0.02)]), 4)
    rows, curves = [], {}
    for name, (nu, kl) in soils.items():
        cryer = Cryer(radius=1.0, load=10.0e3, young=20.0e6, poisson=nu, porosity=0.4,
                      bulk_water=kl, conductivity=2.0e-4, gamma_l=9810.0)
        series = cryer.centre_pressure(taus / cryer.cv) / cryer.p0
        coarse = radial_centre_pressure(cryer, taus, cells=150, dtau=2e-4)
        fine = radial_centre_pressure(cryer, taus, cells=300, dtau=1e-4)
        fine_t = np.linspace(0.001, 0.3, 3000)
        dense = cryer.centre_pressure(fine_t / cryer.cv) / cryer.p0
        k = int(np.argmax(dense))
        rows.append({"soil": name, "eta": cryer.eta, "p0_over_q": cryer.p0 / cryer.load,
                     "peak_over_p0": float(dense[k]), "tau_peak": float(fine_t[k]),
                     "max_diff_coarse": float(np.abs(series - coarse).max()),
                     "max_diff_fine": float(np.abs(series - fine).max())})
        curves[name] = (series, fine)
    print("| soil | eta | p0 / q | peak / p0 | tau at the peak | max diff, 150 cells | "
          "max diff, 300 cells |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['soil']} | {r['eta']:.3f} | {r['p0_over_q']:.4f} | "
              f"{r['peak_over_p0']:.4f} | {r['tau_peak']:.4f} | {r['max_diff_coarse']:.1e} | "
              f"{r['max_diff_fine']:.1e} |")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "cryer_reference.json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.node(), "rows": rows},
        indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 3.6))
    for name, (series, fine) in curves.items():
        line, = ax.plot(taus, series, label=f"series, {name}")
        ax.plot(taus, fine, "o", ms=2.5, color=line.get_color(), label="radial, 300 cells")
    ax.set_xscale("log")
    ax.set_xlabel("tau = c t / a^2")
    ax.set_ylabel("p / p0 at the centre")
    ax.set_title("Cryer's sphere: the reference and its radial check")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.out / "cryer_reference.png", dpi=120)
    print(f"wrote {args.out / 'cryer_reference.json'}, .png")


if __name__ == "__main__":
    main()

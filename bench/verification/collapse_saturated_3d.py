"""The plane-strain check of 3D: the saturated column collapse of Section 4.4 as
a slab 4 dx thick between free-slip walls (`collapse_saturated_3d`) against the 2D scene
at the same dx (`collapse_saturated_psi<psi>`), for psi = -5, 0 and 2.5 degrees.

    python bench/verification/collapse_saturated_3d.py             # runs all six (~2.5 h)
    python bench/verification/collapse_saturated_3d.py --psi 0     # one angle
    python bench/verification/collapse_saturated_3d.py --reuse     # tables finished runs
    python bench/verification/collapse_saturated_3d.py --psi -5 --dx 0.08 --end 0.9
                                        # both at another dx (the slab stays 4 dx thick)
    python bench/verification/collapse_saturated_3d.py --psi -5 --alpha 1 --epsilon 0.5
                                        # the slab at the 2D scene's alpha and epsilon
    python bench/verification/collapse_saturated_3d.py --quick    # psi = 0, dx 0.16, 10 ms

The slab scene carries the 2D scene's artificial viscosity and artificial stress, not its
numbers: at one alpha and epsilon both terms are weaker on a cubic lattice than on a
square one, so `collapse_saturated_3d` sets alpha = 1.25 and epsilon = 0.814 where the 2D
scenes set 1.0 and 0.5 (its TOML says why;
`tests/test_kernels_3d.py::test_the_slab_scene_carries_the_2d_scenes_stabilisation_strengths`
checks the two). Monaghan's viscosity acts as nu = alpha h c / (2 (d + 2)), so the slab's
alpha is the 2D scene's times 5 / 4, the continuum's ratio (on the lattice at h = 1.2 dx
the 3D term is 0.86 as strong for a shear wave and 0.81 for a longitudinal one,
`bench/tools/lattice_sums.py --viscosity`). The artificial stress's moment on the lattice
(bench/tools/lattice_sums.py) is 0.614 as strong on the cubic lattice as on the square one
at h = 1.2 dx and n = 2.55, so the slab's epsilon is the 2D scene's over that ratio.

`--alpha` and `--epsilon` set the slab's own (`--alpha 1 --epsilon 0.5`: the 2D scenes'
numbers). The two flags tag the slab's run directory, JSON and PNG `_a<alpha>` and
`_e<epsilon>` after the other tags; the 2D run is the untagged one, so with `--reuse` it is
shared. Several psi in one command share one JSON and PNG; a later command with the same
tags overwrites them.

The 2D scene runs on one rank, the slab under `mpirun -n NP` (default 2); the runs go to
runs/collapse_saturated_3d/psi<psi>_2d and _3d (with `--dx` or `--end`, psi<psi>_dx<dx>_end<end>_2d
and _3d, and the JSON and PNG named so; `--reuse` keeps a finished one; `--dx` leaves
`initial.water_table` at the scenes' 1.98 m, the top row's centre at dx = 0.04 m, in both
runs alike). Compared:
the run-out at the end (`metrics.collapse.runout_m`, the toe's 99.8th percentile of x
minus the initial front) and the largest 99th percentile of |excess p| over the snapshots
(`metrics.pressure_quality.over_run.abs_excess_p99_max_Pa`; the slab's are read in its x-z
plane, psph/verify/collapse.py `plane_strain_view`). The bar: within 5 % of 2D.
Runs go to runs/collapse_saturated_3d/<name> (`--runs`). Prints a table, writes
<out>/collapse_saturated_3d[<variant>].json and .png (run-out and p99
of |excess| against time, 2D lines, 3D markers).
"""

import argparse
import json
import platform
import tomllib
from datetime import date
from pathlib import Path

from scene_runs import run_scene

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "bench" / "out"
RUNS = ROOT / "runs" / "collapse_saturated_3d"
PSIS = ("-5", "0", "2.5")
BAR = 0.05


def run(out: Path, scene: str, ranks: int, settings: list[str], reuse: bool) -> dict:
    return run_scene(out, scene, ranks, settings, reuse)


def plasticity_settings(psi: str) -> list[str]:
    """The 2D scene's whole [material.plasticity] as --set lines for the slab: the angles
    differ in c and s_f as well as in psi (Table 1)."""
    path = ROOT / "psph" / "scenes" / f"collapse_saturated_psi{psi}.toml"
    plasticity = tomllib.loads(path.read_text())["material"]["plasticity"]
    return [f"material.plasticity.{k}={v}" for k, v in plasticity.items()]


def numbers(s: dict) -> dict:
    m, q = s["metrics"]["collapse"], s["metrics"]["pressure_quality"]
    return {"runout_m": m["runout_m"], "final_height_m": m["final_height_m"],
            "abs_excess_p99_max_Pa": q["over_run"]["abs_excess_p99_max_Pa"],
            "excess_p99_max_Pa": q["over_run"]["excess_p99_max_Pa"],
            "particles": s["particles"], "ranks": s["ranks"], "wall_time_s": s["wall_time_s"],
            "series": {"time_s": m["series"]["time_s"], "runout_m": m["series"]["runout_m"],
                       "abs_excess_p99_Pa": q["series"]["abs_excess_p99_Pa"]}}


def plot(rows: dict, path: Path, tag: str = "") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for k, (psi, r) in enumerate(rows.items()):
        c = f"C{k}"
        for dim, style in (("2d", "-"), ("3d", "o")):
            sr = r[dim]["series"]
            lab = f"psi = {psi}, {dim.upper()}"
            ax1.plot(sr["time_s"], sr["runout_m"], style, color=c, label=lab, mfc="none")
            ax2.plot(sr["time_s"], [v / 1e3 for v in sr["abs_excess_p99_Pa"]], style, color=c,
                     label=lab, mfc="none")
    ax1.set(xlabel="t (s)", ylabel="run-out (m)", title="run-out")
    ax2.set(xlabel="t (s)", ylabel="p99 of |excess p| (kPa)", title="99th percentile of |excess p|")
    ax1.legend(fontsize=7)
    fig.suptitle("collapse_saturated_3d (slab 4 dx thick, slip walls) against the 2D scenes"
                 + (f" ({tag.strip('_')})" if tag else ""))
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--psi", nargs="*", default=list(PSIS), choices=PSIS)
    ap.add_argument("--np", type=int, default=2, help="ranks of the 3D runs")
    ap.add_argument("--reuse", action="store_true", help="keep finished runs")
    ap.add_argument("--dx", type=float, help="particle spacing of both runs (scene: 0.04 m)")
    ap.add_argument("--end", type=float, help="end time of both runs (scene: 1.2 s)")
    ap.add_argument("--alpha", type=float, help="the slab's artificial viscosity alpha")
    ap.add_argument("--epsilon", type=float, help="the slab's artificial stress epsilon")
    ap.add_argument("--runs", type=Path, default=RUNS,
                    help="directory of the runs (default runs/collapse_saturated_3d)")
    ap.add_argument("--quick", action="store_true",
                    help="psi = 0 at dx = 0.16 m to 0.01 s, runs under <out> (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON and PNG (default bench/out)")
    args = ap.parse_args()
    if args.quick:
        args.psi, args.dx, args.end = ["0"], 0.16, 0.01
        if args.runs == RUNS:
            args.runs = args.out / "collapse_saturated_3d-runs"
    common, tag = [], ""
    if args.dx is not None:
        thick = 4 * args.dx  # the slab 4 dx thick, as the scene
        common.append(f"particles.dx={args.dx}")
        slab = [f"domain.max.1={thick}", f"particles.blocks.0.max.1={thick}"]
        tag += f"_dx{args.dx:g}"
    else:
        slab = []
    if args.end is not None:
        common.append(f"time.end={args.end}")
        tag += f"_end{args.end:g}"
    tag3 = tag + (f"_a{args.alpha:g}" if args.alpha is not None else "") + (
        f"_e{args.epsilon:g}" if args.epsilon is not None else "")
    rows = {}
    for psi in args.psi:
        s2 = run(args.runs / f"psi{psi}{tag}_2d", f"collapse_saturated_psi{psi}", 1, common,
                 args.reuse)
        stab = ([f"stabilisation.av_alpha={args.alpha:g}"] if args.alpha is not None else []) + (
            [f"stabilisation.artificial_stress={args.epsilon:g}"]
            if args.epsilon is not None else [])
        s3 = run(args.runs / f"psi{psi}{tag3}_3d", "collapse_saturated_3d", args.np,
                 plasticity_settings(psi) + common + slab + stab, args.reuse)
        r2, r3 = numbers(s2), numbers(s3)
        rows[psi] = {"2d": r2, "3d": r3,
                     "runout_rel": r3["runout_m"] / r2["runout_m"] - 1.0,
                     "abs_excess_p99_rel": r3["abs_excess_p99_max_Pa"]
                     / r2["abs_excess_p99_max_Pa"] - 1.0}
    print(f"{'psi':>5s} {'run-out 2D':>10s} {'3D':>7s} {'diff':>7s} {'p99|ex| 2D kPa':>15s} "
          f"{'3D':>7s} {'diff':>7s} {'within 5 %':>10s}")
    for psi, r in rows.items():
        ok = abs(r["runout_rel"]) <= BAR and abs(r["abs_excess_p99_rel"]) <= BAR
        print(f"{psi:>5s} {r['2d']['runout_m']:10.3f} {r['3d']['runout_m']:7.3f} "
              f"{100 * r['runout_rel']:+6.1f}% {r['2d']['abs_excess_p99_max_Pa'] / 1e3:15.2f} "
              f"{r['3d']['abs_excess_p99_max_Pa'] / 1e3:7.2f} "
              f"{100 * r['abs_excess_p99_rel']:+6.1f}% {'yes' if ok else 'NO':>10s}")
    args.out.mkdir(parents=True, exist_ok=True)
    name = f"collapse_saturated_3d{tag3}"
    (args.out / f"{name}.json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.platform(), "dx": args.dx,
         "end": args.end, "alpha": args.alpha,
         "epsilon": args.epsilon, "rows": rows}, indent=1) + "\n")
    plot(rows, args.out / f"{name}.png", tag3)
    print(f"wrote {args.out / name}.json and .png")


if __name__ == "__main__":
    main()

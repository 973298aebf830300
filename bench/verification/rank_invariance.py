"""The same scenes on 1, 2, 3 and 4 ranks (oversubscribed where cores are fewer) give the
same particles: every snapshot is compared field by field with the 1-rank run.

    python bench/verification/rank_invariance.py           # both scenes, ranks 1 2 3 4
    python bench/verification/rank_invariance.py --ranks 1 2 3
    python bench/verification/rank_invariance.py --quick   # the column to 1 ms, 1 and 2 ranks

Scenes: the consolidation column (coupled, explicit loading then TPI, Shepard filter and
Eq. (47) on) and a dry block falling through every slab onto the floor (migration to
ranks further away, load balancing recuts the slabs). Prints a table of the largest
difference per field, writes <out>/rank_invariance.json and .png (the column's final
pore pressure on each rank count, with that run's slab cuts).
"""

import argparse
import json
import os
import platform
import subprocess
import sys
from datetime import date
from pathlib import Path

import numpy as np

from psph.io.snapshots import read_snapshots

ROOT = Path(__file__).resolve().parents[2]

OUT = Path(__file__).resolve().parents[1] / "out"
FIELDS = ("x", "u", "v", "p", "n", "stress")
COLUMN = ["particles.dx=0.02", "material.k=8e-4", "time.end=0.02", "verification.tv=[]",
          "output.times=[0.005,0.012]", "stabilisation.shepard_every=7", "pressure.beta=0.04"]


# the falling block of tests/helpers.py (tests/scenes/falling_far.toml)
FALLING_FAR = ROOT / "tests" / "scenes" / "falling_far.toml"


def run_case(scene: str, sets: list[str], ranks: int, out: Path) -> dict:
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")
    cmd = ["mpirun", "-n", str(ranks), sys.executable, "-m", "psph", "run", scene,
           "--out", str(out), "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, env=env, check=True, cwd=ROOT)
    return json.loads((out / "summary.json").read_text())


def max_differences(ref: Path, other: Path) -> dict:
    a_all, b_all = read_snapshots(ref), read_snapshots(other)
    assert [s["step"] for s in a_all] == [s["step"] for s in b_all]
    diff = {f: 0.0 for f in FIELDS}
    for a, b in zip(a_all, b_all, strict=True):
        assert np.array_equal(a["id"], b["id"])
        for f in FIELDS:
            diff[f] = max(diff[f], float(np.max(np.abs(a[f] - b[f]))))
    return diff


def main() -> None:
    global OUT
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--quick", action="store_true",
                    help="the column alone to 1 ms on 1 and 2 ranks (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the runs, the JSON and the PNG (default bench/out)")
    args = ap.parse_args()
    OUT = args.out
    OUT.mkdir(parents=True, exist_ok=True)
    work = OUT / "rank_invariance"
    work.mkdir(exist_ok=True)
    scenes = {"column": ("terzaghi_tpi", COLUMN),
              "falling_block": (str(FALLING_FAR), ["decomposition.rebalance_every=50"])}
    if args.quick:  # the column's first millisecond (its loading, 3,500 steps), two snapshots
        short = [s for s in COLUMN if not s.startswith(("time.end", "output.times"))]
        short += ["time.end=0.001", "output.times=[0.0005,0.001]"]
        args.ranks, scenes = [1, 2], {"column": ("terzaghi_tpi", short)}
    rows = []
    for label, (scene, sets) in scenes.items():
        for r in args.ranks:
            summary = run_case(scene, sets, r, work / f"{label}-{r}")
            diff = max_differences(work / f"{label}-1" / "particles.h5",
                                   work / f"{label}-{r}" / "particles.h5") \
                if r != 1 else {f: 0.0 for f in FIELDS}
            rows.append({"scene": label, "ranks": r, "particles": summary["particles"],
                         "steps": summary["steps"], "cuts": summary["load_balance"]["cuts"],
                         "rebalances": summary["load_balance"]["rebalances"],
                         "max_abs_diff": diff,
                         "bitwise": all(v == 0.0 for v in diff.values())})
    print(f"\npsph rank invariance, {date.today()}, {os.cpu_count()} cores")
    print(f"{'scene':14s} {'ranks':>5s} {'rebal.':>6s} " + " ".join(f"{f:>9s}" for f in FIELDS)
          + "  bitwise")
    for r in rows:
        print(f"{r['scene']:14s} {r['ranks']:5d} {r['rebalances']:6d} "
              + " ".join(f"{r['max_abs_diff'][f]:9.2e}" for f in FIELDS)
              + f"  {'yes' if r['bitwise'] else 'NO'}")
    report = {"date": str(date.today()), "machine": platform.node(), "rows": rows}
    (OUT / "rank_invariance.json").write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {OUT / 'rank_invariance.json'}")
    plot(rows, work)
    if not all(r["bitwise"] for r in rows):
        sys.exit(1)


def plot(rows: list[dict], work: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    col = [r for r in rows if r["scene"] == "column"]
    fig, axes = plt.subplots(1, len(col), figsize=(2.2 * len(col) + 1, 5), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, r in zip(axes, col, strict=True):
        s = read_snapshots(work / f"column-{r['ranks']}" / "particles.h5")[-1]
        sc = ax.scatter(s["x"][:, 0], s["x"][:, 1], c=s["p"] / 1e3, s=4, cmap="viridis")
        for c in r["cuts"]:
            ax.axhline(c, color="r", lw=1)
        ax.set_title(f"{r['ranks']} rank(s)\n{'bitwise' if r['bitwise'] else 'DIFFERS'}",
                     fontsize=9)
        ax.set_xticks([])
        ax.set_aspect("equal")
    axes[0].set_ylabel("y (m)")
    fig.colorbar(sc, ax=list(axes), label=f"p (kPa) at t = {s['time']:.3g} s")
    fig.suptitle("column on 1-4 ranks (red: slab cuts)", fontsize=10)
    fig.savefig(OUT / "rank_invariance.png", dpi=110)
    print(f"wrote {OUT / 'rank_invariance.png'}")


if __name__ == "__main__":
    main()

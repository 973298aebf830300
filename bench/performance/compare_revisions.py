"""`make bench` (bench/performance/throughput.py) for two revisions in one run, interleaved.

Each revision is checked out into a temporary git worktree and its own throughput.py runs
there on 1 and 2 ranks, alternating before / after `--repeats` times so that a change of
machine load hits both alike; the best run of each case counts. Prints a table with the
ratio after / before of each case's particle-steps per second, writes
<out>/compare_revisions.json and .png (`--out`, default bench/out). A change that should
cost no more than 3 %, e.g.:

    .venv/bin/python bench/performance/compare_revisions.py --before b5cd252 --after HEAD
    .venv/bin/python bench/performance/compare_revisions.py --before HEAD --quick
        # throughput.py --quick in both, 1 rank, once (revisions that have --quick)
"""

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from datetime import date
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "bench" / "out"


def checkout(rev: str, where: Path) -> str:
    """A detached worktree of `rev` at `where`; returns the full commit."""
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-f", str(where),
                    rev], check=True, capture_output=True)
    return subprocess.run(["git", "-C", str(where), "rev-parse", "HEAD"], check=True,
                          capture_output=True, text=True).stdout.strip()


def throughput(tree: Path, ranks: int, quick: bool = False) -> list[dict]:
    """One run of the tree's own bench/performance/throughput.py on `ranks` ranks."""
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_NUM_THREADS="1")
    subprocess.run(["mpirun", "-n", str(ranks), sys.executable,
                    "bench/performance/throughput.py"] + (["--quick"] if quick else []),
                   cwd=tree, env=env, check=True, capture_output=True)
    name = f"throughput-{'quick-' if quick else ''}{ranks}rank.json"
    return json.loads((tree / "bench" / "out" / name).read_text())["rows"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", required=True, help="git revision")
    ap.add_argument("--after", default="HEAD", help="git revision (default HEAD)")
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--quick", action="store_true",
                    help="throughput.py --quick, 1 rank, one repeat (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON and PNG (default bench/out)")
    args = ap.parse_args()
    if args.quick:
        args.ranks, args.repeats = [1], 1
    tmp = Path(tempfile.mkdtemp(prefix="psph-compare-"))
    trees = {"before": tmp / "before", "after": tmp / "after"}
    commits = {k: checkout(getattr(args, k), p) for k, p in trees.items()}
    try:
        for tree in trees.values():  # compile each tree's kernels once, untimed
            throughput(tree, 1, args.quick)
        best: dict = {}
        for rep in range(args.repeats):
            for ranks in args.ranks:
                for name, tree in trees.items():
                    for row in throughput(tree, ranks, args.quick):
                        key = (ranks, row["case"], name)
                        rate = row["particle_steps_per_s_per_core"]
                        best[key] = max(best.get(key, 0.0), rate)
                        print(f"repeat {rep + 1} ranks {ranks} {name:6s} {row['case']:58s} "
                              f"{rate:12,.0f}", flush=True)
    finally:
        for tree in trees.values():
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                            str(tree)], capture_output=True)
        shutil.rmtree(tmp, ignore_errors=True)
    rows = []
    for (ranks, case, name), rate in sorted(best.items()):
        if name != "before":
            continue
        if (ranks, case, "after") not in best:
            print(f"only before: {ranks} rank(s), {case}")
            continue
        after = best[(ranks, case, "after")]
        rows.append({"ranks": ranks, "case": case, "before": rate, "after": after,
                     "ratio": after / rate})
    print(f"\n{'ranks':>5s} {'case':58s} {'before':>12s} {'after':>12s} {'after/before':>12s}")
    for r in rows:
        print(f"{r['ranks']:5d} {r['case']:58s} {r['before']:12,.0f} {r['after']:12,.0f} "
              f"{r['ratio']:12.3f}")
    print("(particle-steps / s / core, best of the repeats)")
    args.out.mkdir(parents=True, exist_ok=True)
    meta = {"date": str(date.today()), "machine": platform.node(), "commits": commits,
            "repeats": args.repeats, "rows": rows}
    (args.out / "compare_revisions.json").write_text(json.dumps(meta, indent=2) + "\n")
    plot(rows, commits, args.out / "compare_revisions.png")
    print(f"wrote {args.out / 'compare_revisions.json'} and .png")


def plot(rows: list[dict], commits: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 0.5 * len(rows) + 1.8))
    labels = [f"{r['case']}, {r['ranks']} rank(s)" for r in rows]
    ax.barh(range(len(rows)), [r["ratio"] for r in rows], color="tab:blue")
    ax.axvline(1.0, color="k", lw=1)
    ax.axvline(0.97, color="tab:red", ls="--", lw=1, label="3 % slower")
    ax.set_yticks(range(len(rows)), labels, fontsize=8)
    ax.set_xlabel(f"throughput {commits['after'][:7]} / {commits['before'][:7]}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()

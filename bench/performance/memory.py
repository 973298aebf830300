"""Peak memory and set-up time per rank against the particle count and the rank count:
the dry collapse at several dx, one step, one snapshot and one checkpoint, on
1, 2 and 4 ranks (4 oversubscribed on a 2-core machine).

    python bench/performance/memory.py            # dx 0.004, 0.0028, 0.002 (0.5M, 1M, 2M particles)
    python bench/performance/memory.py --quick    # dx 0.01, 0.007 on 1 and 2 ranks (a minute)
    python bench/performance/memory.py --dx 0.0009   # 9.9M particles, 1, 2, 4 ranks (5 min, 6.4 GB)
    python bench/performance/memory.py --plot-only

Each case is one `mpirun -n R python -m psph run collapse_dry --set particles.dx=DX` with
`time.end` one step long; its `summary.json` gives the peak resident memory of every rank
(`memory.peak_rss_bytes_per_rank`, getrusage), the running state's bytes per owned
particle and the set-up seconds. The ratio column is the largest rank's peak over the
1-rank peak at the same dx: 1/R would be perfect division, 1 no division at all. Prints a
table, writes <out>/memory[-quick].json and .png; the run directories are removed.
"""

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
from datetime import date
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "bench" / "out"
FULL = {"dx": (0.004, 0.0028, 0.002), "ranks": (1, 2, 4)}
QUICK = {"dx": (0.01, 0.007), "ranks": (1, 2)}
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none", "NUMBA_NUM_THREADS": "1"}


def run_case(dx: float, ranks: int) -> dict:
    out = OUT / "memory" / f"dx{dx}_r{ranks}"
    shutil.rmtree(out, ignore_errors=True)
    cmd = ["mpirun", "-n", str(ranks), sys.executable, "-m", "psph", "run", "collapse_dry",
           "--set", f"particles.dx={dx}", "--set", "time.end=1e-7", "--out", str(out),
           "--quiet"]
    env = {**os.environ, **MPI_ENV}
    r = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr[-2000:]}")
    s = json.loads((out / "summary.json").read_text())
    shutil.rmtree(out, ignore_errors=True)
    m = s["memory"]
    return {"dx": dx, "ranks": ranks, "particles": s["particles"],
            "peak_rss_bytes_per_rank": m["peak_rss_bytes_per_rank"],
            "state_bytes_per_owned_particle": m["state_bytes_per_owned_particle"],
            "setup_s": s["setup_s"], "wall_time_s": s["wall_time_s"]}


def table(rows: list[dict]) -> None:
    one = {r["dx"]: max(r["peak_rss_bytes_per_rank"]) for r in rows if r["ranks"] == 1}
    print(f"{'particles':>10s} {'ranks':>5s} {'peak RSS per rank (MB)':>28s} "
          f"{'max / 1 rank':>12s} {'state B/particle':>16s} {'set-up s':>9s}")
    for r in rows:
        peaks = r["peak_rss_bytes_per_rank"]
        ratio = max(peaks) / one[r["dx"]] if r["dx"] in one else float("nan")
        print(f"{r['particles']:10d} {r['ranks']:5d} "
              f"{' '.join(f'{p / 2**20:6.0f}' for p in peaks):>28s} {ratio:12.2f} "
              f"{r['state_bytes_per_owned_particle']:16.0f} {r['setup_s']:9.1f}")


def plot(rows: list[dict], name: str = "memory") -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for ranks in sorted({r["ranks"] for r in rows}):
        sel = sorted((r for r in rows if r["ranks"] == ranks), key=lambda r: r["particles"])
        n = [r["particles"] for r in sel]
        ax[0].plot(n, [max(r["peak_rss_bytes_per_rank"]) / 2**30 for r in sel], "o-",
                   label=f"{ranks} rank(s), largest rank")
        ax[1].plot(n, [r["setup_s"] for r in sel], "o-", label=f"{ranks} rank(s)")
    ax[0].set(xlabel="particles", ylabel="peak resident memory per rank (GiB)",
              xscale="log", yscale="log")
    ax[1].set(xlabel="particles", ylabel="set-up time (s)", xscale="log", yscale="log")
    for a in ax:
        a.grid(True, which="both", alpha=0.3)
        a.legend()
    fig.suptitle(f"bench/performance/memory.py, dry collapse, {date.today()}, {platform.node()}")
    fig.tight_layout()
    path = OUT / f"{name}.png"
    fig.savefig(path, dpi=110)
    return path


def main(argv: list[str] | None = None) -> int:
    global OUT
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="dx 0.01 and 0.007 m on 1 and 2 ranks (a minute)")
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--dx", type=float, nargs="+", help="particle spacings instead of the "
                    "full set (on 1, 2 and 4 ranks)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the runs (removed after), the JSON and the PNG "
                         "(default bench/out)")
    args = ap.parse_args(argv)
    OUT = args.out
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / ("memory-quick.json" if args.quick else
                  f"memory-dx{'_'.join(map(str, args.dx))}.json" if args.dx else "memory.json")
    if args.plot_only:
        rows = json.loads(path.read_text())["rows"]
    else:
        cases = QUICK if args.quick else {"dx": tuple(args.dx), "ranks": FULL["ranks"]} \
            if args.dx else FULL
        rows = [run_case(dx, r) for dx in cases["dx"] for r in cases["ranks"]]
        path.write_text(json.dumps({"date": str(date.today()), "machine": platform.node(),
                                    "cpus": os.cpu_count(), "rows": rows}, indent=1) + "\n")
    table(rows)
    print(f"wrote {path} and {plot(rows, path.stem)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

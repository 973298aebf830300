"""Field-scale timing: the retrogressive clay slope of Section 4.5 on 2 ranks.

    python bench/performance/field.py                       # retrogressive_k0_0.5, the full 40 s
    python bench/performance/field.py --window 0.5          # a short window (CI-sized check)
    python bench/performance/field.py --scene retrogressive_k0_1.5
    python bench/performance/field.py --scene slope_section --window 0.5  # the section's throughput
    python bench/performance/field.py --plot-only
    python bench/performance/field.py --quick        # dx = 2 m, a 0.02 s window (a smoke check)

Prints a table (wall time, steps, particle-steps per second per core for the
elastoplastic coupled step over the whole run and over its time steps alone ("stepping":
the stages' seconds, without set-up, gravity loading, snapshots and end-of-run metrics),
the wall time the full 40 s take at that rate, and the time share of each stage) and
writes <out>/field.json (one entry per scene and window; `--out`, default bench/out) and
<out>/field.png, the runs under <out>/field_<scene>[_window]. The bar: the full 40 s of
retrogressive_k0_0.5 in under 30 minutes of wall time on 2 ranks.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import time
from datetime import date
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(__file__).resolve().parents[1] / "out"
FULL = 40.0
BAR_S = 1800.0
# Section 4.5: "the final run-out distance reaches 192 m" (K0 = 0.5); 186 m for K0 = 1.5
PAPER_RUNOUT_M = {"retrogressive_k0_0.5": 192.0, "retrogressive_k0_1.5": 186.0}


SETTINGS: list[str] = []  # further --set lines of the run (--quick's dx)


def run_case(scene: str, end: float | None, out: Path) -> tuple[int, str]:
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")
    cmd = ["mpirun", "-n", "2", sys.executable, "-m", "psph", "run", scene, "--out", str(out),
           "--quiet"]
    if end is not None:
        cmd += ["--set", f"time.end={end}"]
    cmd += [a for kv in SETTINGS for a in ("--set", kv)]
    proc = subprocess.run(cmd, env=env, cwd=ROOT, stderr=subprocess.PIPE, text=True)
    sys.stderr.write(proc.stderr)
    return proc.returncode, proc.stderr


def measure(scene: str, window: float | None) -> dict:
    label = "full" if window is None else f"window {window:g} s"
    out = OUT / f"field_{scene}" if window is None else OUT / f"field_{scene}_window"
    t0 = time.perf_counter()
    code, err = run_case(scene, window, out)
    wall = time.perf_counter() - t0
    entry = {"scene": scene, "case": label, "exit_code": code, "dir": str(out),
             "bench_wall_s": wall}
    failure = re.search(r"numerical failure: step (\d+), t = ([0-9.eE+-]+) s.*", err)
    if failure:  # how far a failed run got (exit 3 names step and time)
        t_reached = float(failure.group(2))
        entry.update(steps_reached=int(failure.group(1)), t_reached_s=t_reached,
                     failure=failure.group(0),
                     projected_full_wall_s=wall * FULL / t_reached)  # start-up included
    summary = out / "summary.json"
    if code == 0 and summary.is_file():
        s = json.loads(summary.read_text())
        loop = s["loop_s"]
        entry.update(
            t_end_s=s["end_time_s"], steps=s["steps"], particles=s["particles"],
            ranks=s["ranks"], wall_s=s["wall_time_s"], loop_s=loop,
            particle_steps_per_s_per_core=s["particle_steps_per_second_per_core"],
            projected_full_wall_s=loop * FULL / s["end_time_s"],
            stage_share={k: v["max_s"] / loop for k, v in s["stage_seconds"].items()},
            # the time steps alone (the stages' seconds, rank with the most): without
            # set-up, gravity loading, snapshots and end-of-run metrics
            stepping_particle_steps_per_s_per_core=s["particles"] * s["steps"] / max(
                sum(v["max_s"] for v in s["stage_seconds"].values()), 1e-300) / s["ranks"],
            metrics=s.get("metrics"))
    return entry


def table(report: dict) -> None:
    print(f"{'scene':24s} {'case':14s} {'exit':>4s} {'t_end':>6s} {'steps':>7s} "
          f"{'N':>6s} {'wall s':>8s} {'Mpsteps/s/core':>14s} {'stepping':>9s} {'40 s wall':>10s}"
          f" {'bar':>5s}")
    for e in report["entries"].values():
        if "loop_s" not in e:
            reached = e.get("t_reached_s")
            where = f"{reached:6.2f} {e['steps_reached']:7d}" if reached is not None else ""
            full = e.get("projected_full_wall_s")
            rate = f"{'':14s} {full / 60:8.1f} m" if full else ""
            print(f"{e['scene']:24s} {e['case']:14s} {e['exit_code']:4d} {where} "
                  f"{'':6s} {e['bench_wall_s']:8.1f} {rate}  (failed: exit {e['exit_code']})")
            continue
        # a finished full run is judged on its own wall time (start-up included)
        full = e["bench_wall_s"] if e["t_end_s"] >= FULL else e["projected_full_wall_s"]
        print(f"{e['scene']:24s} {e['case']:14s} {e['exit_code']:4d} {e['t_end_s']:6.1f} "
              f"{e['steps']:7d} {e['particles']:6d} {e['wall_s']:8.1f} "
              f"{e['particle_steps_per_s_per_core'] / 1e6:14.3f} "
              f"{e.get('stepping_particle_steps_per_s_per_core', float('nan')) / 1e6:9.3f} "
              f"{full / 60:8.1f} m "
              f"{'ok' if full < BAR_S else 'over':>5s}")
    done = [e for e in report["entries"].values()
            if (e.get("metrics") or {}).get("collapse")]
    if done:
        print(f"\n{'scene':24s} {'case':14s} {'slides':>6s} {'at (s)':28s} {'run-out m':>9s} "
              f"{'toe x m':>8s} {'paper':>6s} {'back scarp m':>12s}")
    for e in done:
        c = e["metrics"]["collapse"]
        at = ", ".join(f"{t:.1f}" for t in c.get("slide_times_s", []))
        paper = PAPER_RUNOUT_M.get(e["scene"], float("nan"))
        print(f"{e['scene']:24s} {e['case']:14s} {c.get('slides', 0):6d} {at:28s} "
              f"{c['runout_m']:9.1f} {c['toe_m']:8.1f} {paper:6.0f} {c['back_scarp_m']:12.1f}")


def plot(report: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    timed = [e for e in report["entries"].values() if "projected_full_wall_s" in e]
    entries = [e for e in timed if "stage_share" in e]
    if not timed:
        return
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 4.5))
    labels = [f"{e['scene']}\n{e['case']}" + (f" (failed at {e['t_reached_s']:.2f} s)"
                                              if "t_reached_s" in e else "") for e in timed]
    ax1.barh(labels, [(e["bench_wall_s"] if e.get("t_end_s", 0.0) >= FULL
                       else e["projected_full_wall_s"]) / 60 for e in timed], color="tab:blue")
    ax1.axvline(BAR_S / 60, color="r", ls="--", label="bar: 30 min")
    ax1.set_xlabel("wall time for 40 s of physical time on 2 ranks (min)")
    ax1.legend()
    stages = sorted({k for e in entries for k in e["stage_share"]})
    left = [0.0] * len(entries)
    for st in stages:
        w = [100 * e["stage_share"].get(st, 0.0) for e in entries]
        ax2.barh([f"{e['scene']}\n{e['case']}" for e in entries], w, left=left, label=st)
        left = [a + b for a, b in zip(left, w, strict=True)]
    ax2.set_xlabel("share of loop time (%), rank with the most")
    ax2.legend(fontsize=7, loc="lower left")
    fig.suptitle(f"bench/performance/field.py, {report['date']}, 2 ranks", fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "field.png", dpi=100)
    print(f"wrote {OUT / 'field.png'}")


def main() -> None:
    global OUT
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="retrogressive_k0_0.5")
    ap.add_argument("--window", type=float, default=None, help="end time (s); default 40")
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--quick", action="store_true",
                    help="the scene at dx = 2 m, 0.02 s of gravity loading, a 0.02 s window "
                         "(a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the runs, the JSON and the PNG (default bench/out)")
    args = ap.parse_args()
    OUT = args.out
    if args.quick:
        args.window = 0.02
        SETTINGS.extend(["particles.dx=2.0", "initial.equilibrate=0.02"])
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "field.json"
    report = json.loads(path.read_text()) if path.is_file() else {"entries": {}}
    if not args.plot_only:
        e = measure(args.scene, args.window)
        report["entries"][f"{e['scene']} / {e['case']}"] = e
        report["date"] = str(date.today())
        report["machine"] = os.uname().nodename + f", {os.cpu_count()} cores"
        path.write_text(json.dumps(report, indent=1) + "\n")
    table(report)
    plot(report)


if __name__ == "__main__":
    main()

"""The default run (`make run`: the paper's Section 4.1 column, the projection at
C_CFL^s = 0.4) to T_v = 1 on the ranks it is started on, against Terzaghi's solution:
max |p - p_a| / q at every stated T_v, the settlement error, the wall time of the run and
its CG iterations. The test `tests/test_verification_mpi.py` runs its first window (to
T_v = 0.2, where the largest error is); this is the whole run.

    mpirun -n 2 .venv/bin/python bench/verification/default_run.py     # ~2.5 min here
    mpirun -n 1 .venv/bin/python bench/verification/default_run.py \
        --set pressure.tolerance=1e-4 --set 'verification.tv=[0.05, 0.1, 0.2]'  # a variant
    mpirun -n 2 .venv/bin/python bench/verification/default_run.py --scene terzaghi_3d
        # the same column in 3D between four slip walls, ~15 min here
    mpirun -n 2 .venv/bin/python bench/verification/default_run.py --quick
        # the tests' column (dx = 0.02 m, k = 8e-4 m/s) to T_v = 0.05, seconds

Prints a table, writes <out>/default_run-np<P>[-<tag>].json and .png (error against
T_v; `<scene>-np<P>` for another --scene); --set overrides a scene key as `psph run --set`
does (the tag names the variant).
"""

import argparse
import json
import platform
import tempfile
from datetime import date
from pathlib import Path

from mpi4py import MPI

from psph.app.run import run
from psph.config.load import load_scene

OUT = Path(__file__).resolve().parents[1] / "out"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a scene override (repeatable)")
    ap.add_argument("--tag", default="", help="suffix of the output files")
    ap.add_argument("--scene", default="terzaghi",
                    help="a Terzaghi column scene: terzaghi (default) or terzaghi_3d")
    ap.add_argument("--quick", action="store_true",
                    help="dx = 0.02 m, k = 8e-4 m/s, to T_v = 0.05 (a smoke check; tag quick)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of the JSON and PNG (default bench/out)")
    args = ap.parse_args()
    if args.quick:
        args.set += ["particles.dx=0.02", "material.k=8e-4", "verification.tv=[0.05]"]
        args.tag = args.tag or "quick"
    comm = MPI.COMM_WORLD
    work = comm.bcast(tempfile.mkdtemp(prefix="psph-default-") if comm.rank == 0 else None)
    summary = run(load_scene(args.scene, args.set), Path(work) / args.scene, comm=comm,
                  quiet=True)
    if comm.rank != 0:
        return
    err = summary["errors"]
    rows = [(float(tv), e["max_abs_p_error_over_q"]) for tv, e in err["pressure"].items()]
    result = {"date": date.today().isoformat(), "machine": platform.node(),
              "scene": args.scene, "particles": summary["particles"],
              "ranks": comm.size, "overrides": args.set,
              "wall_time_s": summary["wall_time_s"],
              "loop_s": summary["loop_s"], "steps": summary["steps"],
              "cg_iterations_per_step": summary["pressure_solve"]["iterations_mean"],
              "p_error_over_q": dict(rows),
              "settlement_error": err["settlement_max_abs_error_over_final"],
              "within_one_percent": bool(all(e < 0.01 for _, e in rows)
                                        and err["settlement_max_abs_error_over_final"] < 0.01)}
    print(f"{args.scene} on {comm.size} rank(s) {' '.join(args.set)}: {result['steps']} steps, "
          f"{result['wall_time_s']:.1f} s, {result['cg_iterations_per_step']:.2f} CG it/step")
    print("| T_v | max abs(p - p_a) / q |\n|---|---|")
    for tv, e in rows:
        print(f"| {tv:g} | {e:.4f} |")
    print(f"settlement error {result['settlement_error']:.4f}; within 1 %: "
          f"{result['within_one_percent']}")
    args.out.mkdir(parents=True, exist_ok=True)
    name = "default_run" if args.scene == "terzaghi" else args.scene
    stem = args.out / (f"{name}-np{comm.size}" + (f"-{args.tag}" if args.tag else ""))
    stem.with_suffix(".json").write_text(json.dumps(result, indent=1))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.2))
    ax.plot([tv for tv, _ in rows], [100 * e for _, e in rows], "o-")
    ax.axhline(1.0, color="k", ls="--", lw=0.8, label="1 % of q")
    ax.set(xscale="log", xlabel="T_v", ylabel="max |p - p_a| / q (%)",
           title=f"{args.scene}, {comm.size} rank(s), {result['wall_time_s']:.0f} s")
    ax.legend()
    fig.tight_layout()
    fig.savefig(stem.with_suffix(".png"), dpi=120)


if __name__ == "__main__":
    main()

"""psph, coupled flow-deformation SPH of saturated soil: run, list, validate, plot, export.

Exit codes (docs/guide/exit_codes.md): 0 done, 1 other error, 2 bad input, 3 numerical
failure, 74 output file system full (the last checkpoint named), 75 stopped by a signal
after writing a checkpoint (rerun with --restart). Only rank 0 prints. Nothing numerical
here."""

import argparse
import sys
import traceback
from pathlib import Path

from psph.errors import Interrupted, NumericalError, OutputError, SceneError


def _rank() -> int:
    from mpi4py import MPI

    return MPI.COMM_WORLD.Get_rank()


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="psph", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command")
    r = sub.add_parser("run", help="run a scene (built-in name or TOML file)")
    r.add_argument("scene")
    r.add_argument("--out", type=Path, help="output directory (default runs/<name>)")
    r.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a scene value (repeatable)")
    r.add_argument("--restart", type=Path, metavar="CHECKPOINT",
                   help="continue from OUT/checkpoint.h5 (default --out: its directory)")
    r.add_argument("--quiet", action="store_true", help="no progress output")
    sub.add_parser("list", help="built-in scenes")
    v = sub.add_parser("validate", help="parse + validate, print the resolved scene")
    v.add_argument("scene")
    v.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    pl = sub.add_parser("plot", help="PNG pictures of a run's output directory")
    pl.add_argument("out", type=Path)
    pl.add_argument("--field", default="p")
    ex = sub.add_parser("export", help="snapshots as VTU files (+ .pvd) or XDMF, via meshio")
    ex.add_argument("out", type=Path)
    ex.add_argument("--format", choices=("vtu", "xdmf"), default="vtu")
    return p


class _ArgError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise _ArgError(message)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv:
        argv = ["run", "terzaghi"]
    parser = _parser()
    parser.__class__ = _Parser
    for action in parser._subparsers._group_actions:
        for sp in action.choices.values():
            sp.__class__ = _Parser
    rank0 = _rank() == 0
    try:
        args = parser.parse_args(argv)
        return _dispatch(args, rank0)
    except _ArgError as e:
        if rank0:
            print(f"psph: error: {e}", file=sys.stderr)
        return 2
    except SceneError as e:
        if rank0:
            print(f"psph: error: {e}", file=sys.stderr)
        return 2
    except NumericalError as e:
        if rank0:
            print(f"psph: numerical failure: {e}", file=sys.stderr)
        return 3
    except OutputError as e:  # raised by every rank together (psph/io/space.py)
        if rank0:
            print(f"psph: error: {e}", file=sys.stderr)
        return OutputError.exit_code
    except Interrupted as e:
        if rank0:
            print(f"psph: {e}", file=sys.stderr)
        return Interrupted.exit_code
    except Exception:
        # an error on one rank must not leave the others waiting in a collective
        print(f"psph: internal error on rank {_rank()}:", file=sys.stderr)
        traceback.print_exc()
        from mpi4py import MPI

        if MPI.COMM_WORLD.Get_size() > 1:
            MPI.COMM_WORLD.Abort(1)
        return 1


def _dispatch(args, rank0: bool) -> int:
    from psph.config import load as sc

    if args.command == "list":
        if rank0:
            for name in sc.builtin_names():
                text, label = sc.read_scene_text(name)
                desc = sc.parse_toml(text, label).get("description", "")
                print(f"{name:24s} {desc}")
        return 0
    if args.command == "validate":
        s = sc.load_scene(args.scene, args.set)
        if rank0:
            print(sc.to_toml(s), end="")
        return 0
    if args.command == "plot":
        from psph.analysis.plot import plot_run

        if rank0:
            for path in plot_run(args.out, args.field):
                print(f"wrote {path}")
        return 0
    if args.command == "export":
        from psph.io.export import export_run

        if rank0:
            for path in export_run(args.out, args.format):
                print(f"wrote {path}")
        return 0
    if args.command == "run":
        s = sc.load_scene(args.scene, args.set)
        out = args.out or (args.restart.parent if args.restart else Path("runs") / s.name)
        from psph.app.run import run

        summary = run(s, out, quiet=args.quiet, restart=args.restart)
        if rank0:
            msg = (f"psph: {s.name}: {summary['steps']} steps, t = {summary['end_time_s']:.4g} s "
                   f"in {summary['wall_time_s']:.1f} s on {summary['ranks']} rank(s), "
                   f"{summary['steps_per_second']:.0f} steps/s -> {out}")
            if args.restart:
                msg += f" (restarted: {summary['steps_this_run']} steps in this run)"
            print(msg)
            err = summary.get("errors")
            if err and err.get("max_abs_p_error_over_q") is not None:
                print(f"psph: max |p - p_a|/q = {err['max_abs_p_error_over_q']:.4f}, "
                      f"settlement error = {err['settlement_max_abs_error_over_final']:.4f}")
        return 0
    _parser().print_help()
    return 1

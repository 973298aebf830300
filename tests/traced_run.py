"""`python -m psph ...` under tracemalloc: every rank's peak of traced memory (numpy
array data and Python objects allocated after the imports) gathered to rank 0 and
written as JSON to the path of the first argument (tests/test_memory_bound.py).

    mpirun -n 2 python tests/traced_run.py PEAKS.json run collapse_dry --set ...
"""

import json
import sys
import tracemalloc

from mpi4py import MPI

from psph.app.cli import main


def traced(argv: list[str]) -> tuple[int, int]:
    """(exit code, this rank's peak traced bytes) of the command line `argv`."""
    tracemalloc.start()
    code = main(argv)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return code, peak


if __name__ == "__main__":
    code, peak = traced(sys.argv[2:])
    peaks = MPI.COMM_WORLD.gather(peak)
    if MPI.COMM_WORLD.Get_rank() == 0:
        with open(sys.argv[1], "w") as f:
            json.dump({"exit": code, "peak_traced_bytes_per_rank": peaks}, f)
    sys.exit(code)

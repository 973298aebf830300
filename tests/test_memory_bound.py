"""No rank holds the whole scene at any point of a run or of its restart (issue 15): the
peak memory a rank allocates grows with its share of the particles, not with the global
count.

Measured with tracemalloc (numpy array data and Python objects; tests/traced_run.py),
whose peak over a whole run includes every transient array: set-up (census, seeding,
slab cuts), the step, the snapshot and checkpoint writes, the end-of-run metrics read
back from particles.h5, and a restart's read of the checkpoint. The dry collapse at
dx = 0.01 and 0.005 m (80,000 and 320,000 particles), one step, then a restart for one
more; the slope of the peak against the particle count is compared between 1 and 2
ranks. Measured 2026-11-30: 1 rank 1190 B per particle, 2 ranks 615 B on each rank
(ratio 0.52); before the end-of-run metrics were distributed rank 0 read every snapshot
whole, and the same test measured 0.62 and failed.

The dry collapse has no pore pressure, so its metrics read x and u only: the pressure
quality's reads and halo (`psph/verify/distributed.py`) are not under this bound; they
hold this rank's share and a 2h halo by construction (tests/test_distributed_metrics.py).
What this cannot see: an array of a few bytes per global particle (a float64 mask is
8 B, under 1 % of the slope); those are ruled out by construction
(psph/decomposition/census.py, psph/geometry/lattice.py, psph/io/checkpoint.py) and by
tests/test_setup.py.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

DRIVER = Path(__file__).parent / "traced_run.py"
SIZES = {0.01: 80_000, 0.005: 320_000}
BOUND = 0.6  # largest rank's slope over the 1-rank slope; 1/2 is perfect division


def _peaks(tmp: Path, ranks: int, dx: float, *args: str) -> list[int]:
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")
    report = tmp / f"peaks_{ranks}_{dx}_{len(args)}.json"
    out = tmp / f"r{ranks}_dx{dx}"
    cmd = ["mpirun", "-n", str(ranks), sys.executable, str(DRIVER), str(report), "run",
           "collapse_dry", "--out", str(out), "--quiet", "--set", f"particles.dx={dx}",
           "--set", "time.end=1e-9", *args]
    res = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    return json.loads(report.read_text())["peak_traced_bytes_per_rank"]


def test_peak_memory_per_rank_follows_the_ranks_share_in_a_run_and_its_restart(tmp_path):
    peaks = {}  # (phase, ranks, dx) -> peak per rank
    for ranks in (1, 2):
        for dx in SIZES:
            peaks["run", ranks, dx] = _peaks(tmp_path, ranks, dx)
            checkpoint = tmp_path / f"r{ranks}_dx{dx}" / "checkpoint.h5"
            peaks["restart", ranks, dx] = _peaks(tmp_path, ranks, dx, "--restart",
                                                 str(checkpoint), "--set", "time.end=2e-5")
    for phase in ("run", "restart"):
        slope = {ranks: max((b - a) / (SIZES[0.005] - SIZES[0.01]) for a, b in zip(
            peaks[phase, ranks, 0.01], peaks[phase, ranks, 0.005], strict=True))
            for ranks in (1, 2)}
        ratio = slope[2] / slope[1]
        assert ratio < BOUND, (f"{phase}: {slope[1]:.0f} B per particle on 1 rank, "
                               f"{slope[2]:.0f} on the largest of 2 ranks ({ratio:.2f})")

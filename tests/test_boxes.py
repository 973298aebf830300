"""Boxes along two axes (issue 38, `psph/decomposition/boxes.py`): the layout rule, the
owner and halo kernels against brute force, and whole runs on 4 ranks (2 x 2 boxes)
bit for bit equal to 1 rank in 3D and 2D, through rebalances, a surface floor's
boundary particles, the projection's CG, and a restart from 4 ranks on 2.

The 4- and 2-rank runs are `mpirun` subprocesses (4 ranks share this machine's 2 cores:
slower, not different)."""

import json
import shutil

import numpy as np
import pytest

from psph.app.run import run
from psph.config.load import load_scene
from psph.decomposition.boxes import box_partners, choose_layout
from psph.kernels.packing import (
    box_halo,
    box_owners,
    compact_rows,
    group_by_rank,
    split_by_owner,
)
from tests.helpers import compare_runs
from tests.test_mpi_3d import COLUMN_3D
from tests.test_rank_counts import _mpirun_scene


@pytest.mark.parametrize("extent, size, cuts, layout", [
    ((1.0, 1.0), 4, "auto", (2, 2)),    # a square: the busiest box holds half a slab's halo
    ((6.0, 1.0), 4, "auto", (4, 1)),    # long and narrow: slabs
    ((1.0, 1.0), 2, "auto", (2, 1)),    # two ranks: always slabs
    ((1.0, 1.0), 7, "auto", (7, 1)),    # a prime count: slabs
    ((6.0, 1.0), 4, "boxes", (2, 2)),   # forced
    ((1.0, 1.0), 4, "slabs", (4, 1)),
    ((1.0, 1.0), 7, "boxes", None),     # no factors above 1
    ((2.0, 1.0), 8, "auto", (4, 2)),
])
def test_the_layout_has_the_least_halo_on_its_busiest_rank(extent, size, cuts, layout):
    assert choose_layout(extent, size, cuts) == layout


def test_box_owners_and_halo_match_a_brute_force_search():
    rng = np.random.default_rng(5)
    x = rng.uniform(0.0, 1.0, (400, 3))
    cuts0 = np.array([-np.inf, 0.4, 0.7, np.inf])
    cuts1 = np.array([[-np.inf, 0.5, np.inf], [-np.inf, 0.3, np.inf],
                      [-np.inf, 0.6, np.inf]])  # boxes of the three slabs do not line up
    a0, a1, width = 2, 0, 0.08
    owner = np.zeros(len(x), np.int64)
    box_owners(x, len(x), a0, a1, cuts0, cuts1, owner)
    lo = np.array([[cuts0[r // 2], cuts1[r // 2, r % 2]] for r in range(6)])
    hi = np.array([[cuts0[r // 2 + 1], cuts1[r // 2, r % 2 + 1]] for r in range(6)])
    c = x[:, [a0, a1]]
    inside = [np.all((c >= lo[r]) & (c < hi[r]), axis=1) for r in range(6)]
    assert np.array_equal(owner, np.argmax(inside, axis=0))
    assert np.all(np.sum(inside, axis=0) == 1)
    me = 3
    mine = np.flatnonzero(owner == me)
    xs = np.ascontiguousarray(x[mine])
    dest, rows = np.zeros(4, np.int64), np.zeros(4, np.int64)
    assert box_halo(xs, len(xs), a0, a1, cuts0, cuts1, width, me, dest, rows) < 0  # short
    dest, rows = np.zeros(4000, np.int64), np.zeros(4000, np.int64)
    m = box_halo(xs, len(xs), a0, a1, cuts0, cuts1, width, me, dest, rows)
    got = set(zip(dest[:m].tolist(), rows[:m].tolist(), strict=True))
    cm = c[mine]
    want = {(r, i) for r in range(6) if r != me for i in range(len(xs))
            if np.all((cm[i] >= lo[r] - width) & (cm[i] < hi[r] + width))}
    assert got == want and m == len(want) and len(want) > 0



def test_box_partners_are_the_boxes_within_the_width():
    """Three slabs of two boxes whose boxes do not line up: the partners of each box are
    those whose closed extents come within the width along both axes (brute force), the
    relation is symmetric, and the far slab's boxes are no partners of the first's."""
    cuts0 = np.array([-np.inf, 1.0, 2.0, np.inf])
    cuts1 = np.array([[-np.inf, 0.5, np.inf], [-np.inf, 0.3, np.inf],
                      [-np.inf, 0.6, np.inf]])
    width = 0.1
    lo = np.array([[cuts0[r // 2], cuts1[r // 2, r % 2]] for r in range(6)])
    hi = np.array([[cuts0[r // 2 + 1], cuts1[r // 2, r % 2 + 1]] for r in range(6)])
    got = {r: set(box_partners(cuts0, cuts1, r, width).tolist()) for r in range(6)}
    for r in range(6):
        gap = np.maximum(lo - hi[r], lo[r] - hi)  # per axis, the gap between the boxes
        want = {q for q in range(6) if q != r and np.all(gap[q] <= width)}
        assert got[r] == want
    assert all(r in got[q] for r in range(6) for q in got[r])
    assert got[0] == {1, 2, 3} and got[5] == {3, 4}
    # a near tie, where lo_r <= hi_me + w and hi_r >= lo_me - w round differently
    cuts0 = np.array([-np.inf, 0.9385958677423489, 1.038595867742349, np.inf])
    cuts1 = np.array([[-np.inf, np.inf]] * 3)
    got = {r: set(box_partners(cuts0, cuts1, r, 0.1).tolist()) for r in range(3)}
    assert all(r in got[q] for r in range(3) for q in got[r]), got


def test_row_moves_match_numpy():
    """The migration's kernels against their numpy forms: the split by owner
    (flatnonzero), the counting sort by rank (a stable argsort and a bincount) and the
    in-place compaction (fancy indexing)."""
    rng = np.random.default_rng(7)
    owner = rng.integers(0, 5, 300)
    keep, leave, dest = (np.zeros(300, np.int64) for _ in range(3))
    nk, nl = split_by_owner(owner, 300, 2, keep, leave, dest)
    assert np.array_equal(keep[:nk], np.flatnonzero(owner == 2))
    assert np.array_equal(leave[:nl], np.flatnonzero(owner != 2))
    assert np.array_equal(dest[:nl], owner[owner != 2])
    rows = rng.permutation(1000)[:nl]
    counts, grouped = np.full(5, -1, np.int64), np.zeros(nl, np.int64)
    group_by_rank(dest, rows, nl, counts, grouped)
    assert np.array_equal(grouped, rows[np.argsort(dest[:nl], kind="stable")])
    assert np.array_equal(counts, np.bincount(dest[:nl], minlength=5))
    fields = (rng.normal(size=(300, 3)), rng.normal(size=(300, 1)))
    want = [f[keep[:nk]].copy() for f in fields]
    compact_rows(fields, keep, nk)
    for f, w in zip(fields, want, strict=True):
        assert np.array_equal(f[:nk], w)


def _summary(out) -> dict:
    return json.loads((out / "summary.json").read_text())


def test_3d_boxes_on_four_ranks_equal_one_rank_and_restart_on_two(tmp_path):
    """The Section 4.1 column in 3D (the projection; cut in 2 x 2 boxes along z and x) and
    a quarter column collapsing on a surface floor (boundary particles, rebalances; 2 x 2
    along x and y, the auto layout's choice): 4 ranks equal 1 rank bit for bit, with the
    same CG iterations; the column's checkpoint written on 4 ranks mid-run and restarted
    on 2 (slabs), and its 1-rank checkpoint restarted on 4 (boxes), continue the same
    bits."""
    from mpi4py import MPI

    column = COLUMN_3D + ["decomposition.cuts='boxes'"]
    mid = ["checkpoint.every=200", "checkpoint.at_end=false"]
    run(load_scene("terzaghi_3d", column + mid), tmp_path / "one", comm=MPI.COMM_SELF,
        quiet=True)
    _mpirun_scene(4, "terzaghi_3d", tmp_path / "four", column + mid)
    assert compare_runs(tmp_path / "one" / "particles.h5",
                        tmp_path / "four" / "particles.h5") is None
    four = _summary(tmp_path / "four")
    assert four["decomposition"]["shape"] == [2, 2] and four["decomposition"]["axes"] == [2, 0]
    assert four["pressure_solve"] == _summary(tmp_path / "one")["pressure_solve"]
    shutil.copytree(tmp_path / "four", tmp_path / "four_two")
    _mpirun_scene(2, "terzaghi_3d", tmp_path / "four_two",
                  COLUMN_3D + ["decomposition.cuts='auto'"],  # slabs on 2 ranks
                  restart=tmp_path / "four_two" / "checkpoint.h5")
    assert _summary(tmp_path / "four_two")["restarted_from"]
    assert compare_runs(tmp_path / "one" / "particles.h5",
                        tmp_path / "four_two" / "particles.h5") is None
    shutil.copytree(tmp_path / "one", tmp_path / "one_four")  # and from 1 rank onto boxes
    _mpirun_scene(4, "terzaghi_3d", tmp_path / "one_four", column,
                  restart=tmp_path / "one_four" / "checkpoint.h5")
    assert _summary(tmp_path / "one_four")["decomposition"]["shape"] == [2, 2]
    assert compare_runs(tmp_path / "one" / "particles.h5",
                        tmp_path / "one_four" / "particles.h5") is None

    collapse = ["particles.dx=0.1", "time.end=0.1", "output.interval=0.05"]
    run(load_scene("collapse_3d", collapse), tmp_path / "c_one", comm=MPI.COMM_SELF,
        quiet=True)
    _mpirun_scene(4, "collapse_3d", tmp_path / "c_four", collapse)
    assert compare_runs(tmp_path / "c_one" / "particles.h5",
                        tmp_path / "c_four" / "particles.h5") is None
    c_four = _summary(tmp_path / "c_four")
    assert c_four["decomposition"]["shape"] == [2, 2]
    assert c_four["load_balance"]["rebalances"] > 0


@pytest.mark.parametrize("ranks, shape, end", [(4, [2, 2], 0.01), (6, [3, 2], 0.004)])
def test_2d_boxes_equal_one_rank(tmp_path, ranks, shape, end):
    """The saturated collapse (TPI, walls, K0) in 2D, cut in 2 x 2 and in 3 x 2 boxes; in
    3 x 2 the first and the last slab's boxes are no partners, so rows move
    point-to-point between partners only. The same bits as one rank."""
    from mpi4py import MPI

    settings = [f"time.end={end}", f"output.interval={end / 2}"]
    run(load_scene("collapse_saturated_psi0", settings), tmp_path / "one",
        comm=MPI.COMM_SELF, quiet=True)
    _mpirun_scene(ranks, "collapse_saturated_psi0", tmp_path / "many",
                  settings + ["decomposition.cuts='boxes'"])
    assert compare_runs(tmp_path / "one" / "particles.h5",
                        tmp_path / "many" / "particles.h5") is None
    d = _summary(tmp_path / "many")["decomposition"]
    assert d["shape"] == shape
    if ranks == 6:
        cuts0 = np.array([-np.inf] + d["cuts0"] + [np.inf])
        cuts1 = np.array([[-np.inf] + row + [np.inf] for row in d["cuts1"]])
        assert not {4, 5} & set(box_partners(cuts0, cuts1, 0, 0.2).tolist())  # slabs > 1 m


def test_boxes_hold_less_halo_than_slabs_on_a_3d_block(tmp_path):
    """A cube of 20 x 20 x 20 particles on 4 ranks: the busiest box holds less halo than
    the busiest slab (the scaling model's point, measured)."""
    block = ["particles.dx=0.05", "domain.max=[1.0, 1.0, 1.0]",
             "particles.blocks=[{min=[0.0, 0.0, 0.0], max=[1.0, 1.0, 1.0]}]",
             "time.end=0.0002",
             "verification.tv=[]", "output.times=[]", "decomposition.axis='x'",
             "pressure.recycle=0"]
    halo = {}
    for cuts in ("slabs", "boxes"):
        _mpirun_scene(4, "terzaghi_3d", tmp_path / cuts, block + [f"decomposition.cuts='{cuts}'"])
        d = _summary(tmp_path / cuts)["decomposition"]
        assert sum(d["owned_per_rank"]) == 8000
        halo[cuts] = max(d["halo_rows_per_rank"])
    assert halo["boxes"] < 0.75 * halo["slabs"], halo


def test_boxes_forced_on_two_ranks_is_bad_input(tmp_path):
    """Two ranks have no factors n0 x n1 above 1: exit 2 naming the key, nothing written."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl="self,vader,tcp",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", NUMBA_NUM_THREADS="1")
    out = tmp_path / "out"
    r = subprocess.run(["mpirun", "-n", "2", sys.executable, "-m", "psph", "run", "collapse_3d",
                        "--out", str(out), "--set", "decomposition.cuts='boxes'"], env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r.stderr[-2000:]
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("psph: error")]
    assert lines and all("decomposition.cuts = 'boxes': 2 ranks have no factors" in ln
                         for ln in lines), r.stderr[-2000:]
    assert "Traceback" not in r.stderr and not out.exists()

"""Snapshot metrics over ranks without global arrays (issue 15; psph/verify/distributed.py):
order statistics and percentiles equal numpy's bit for bit on any partition, extremes
name the particle numpy names, the slab-with-halo rows give every particle its neighbours,
and the collapse and pressure-quality metrics of a snapshot read in shares equal the
serial ones (the checkerboard index to rounding)."""

import numpy as np
import pytest
from mpi4py import MPI

from psph.verify.collapse import collapse_metrics
from psph.verify.distributed import extreme, percentiles, share, with_halo
from psph.verify.pressure import checkerboard_index, neighbour_pairs

QS = [0, 1, 5, 37.5, 50, 95, 99, 99.8, 100]


def _samples():
    rng = np.random.default_rng(7)
    for trial in range(60):
        n = int(rng.integers(1, 400))
        v = rng.normal(size=n) * 10.0 ** int(rng.integers(-3, 6))
        if trial % 3 == 0:
            v = np.round(v)  # ties
        if trial % 5 == 0:
            v[: n // 2] = 0.0
        yield v


def test_percentiles_and_extremes_equal_numpy_on_one_process():
    for v in _samples():
        assert percentiles(v, QS, MPI.COMM_SELF) == list(np.percentile(v, QS))
        ids = np.arange(len(v))
        assert extreme(v, ids, np.c_[v, v], MPI.COMM_SELF, True)[:2] == \
            (v.max(), int(np.argmax(v)))
        assert extreme(v, ids, np.c_[v, v], MPI.COMM_SELF, False)[:2] == \
            (v.min(), int(np.argmin(v)))


def _lattice(n=30, dx=0.1):
    g = (np.arange(n) + 0.5) * dx
    x = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    return x + np.random.default_rng(3).normal(scale=0.05 * dx, size=x.shape)


@pytest.mark.mpi(min_size=2)
def test_shares_on_two_ranks_give_the_serial_metrics():
    comm = MPI.COMM_WORLD
    for v in _samples():
        lo, hi = share(len(v), comm)
        assert percentiles(v[lo:hi], QS, comm) == list(np.percentile(v, QS))
        ids = np.arange(len(v))
        assert extreme(v[lo:hi], ids[lo:hi], np.c_[v, v][lo:hi], comm, True)[:2] == \
            (v.max(), int(np.argmax(v)))

    x = _lattice()
    x0 = x.copy()
    x[:, 0] += 0.3 * x[:, 1] ** 2  # a sheared mass: a toe, a scarp
    lo, hi = share(len(x), comm)
    assert collapse_metrics(x[lo:hi], x0[lo:hi], 0.1, comm) == collapse_metrics(x, x0, 0.1)

    h = 0.12
    f = np.sin(7 * x[:, 0]) + np.where((np.arange(len(x)) % 2) == 0, 0.2, -0.2)
    xs, fs, n_owned = with_halo(x[lo:hi], {"f": f[lo:hi]}, 2 * h, comm)
    assert comm.allreduce(n_owned) == len(x)
    i, j, _ = neighbour_pairs(x, 2 * h)
    mine = {tuple(p) for p in xs[:n_owned]}
    own = np.array([tuple(p) in mine for p in x])
    need = {tuple(p) for p in x[np.unique(j[own[i]])]}  # every neighbour of an owned row
    assert need <= {tuple(p) for p in xs}
    cb = checkerboard_index(xs, fs["f"], h, None, None, comm, n_owned)
    assert cb == pytest.approx(checkerboard_index(x, f, h), rel=1e-12)


@pytest.mark.mpi(min_size=2)
def test_collapse_verification_on_two_ranks_equals_one_process(tmp_path_factory):
    """The whole end-of-run block of a saturated collapse (psph.verify.collapse_verification:
    collapse metrics and their series with the dissipated plastic work (an exact sum),
    slides, every snapshot's pressure quality) read in shares on 2 ranks equals the
    one-process block: exactly, but the checkerboard indices (their sums in another
    order) to a relative 1e-12."""
    from psph.app.run import run
    from psph.config.load import load_scene
    from psph.verify.collapse import collapse_verification
    from tests.helpers import shared_tmp

    comm = MPI.COMM_WORLD
    out = shared_tmp(comm, tmp_path_factory)
    scene = load_scene("collapse_saturated_psi0", ["time.end=0.01", "output.interval=0.005"])
    if comm.Get_rank() == 0:
        run(scene, out, comm=MPI.COMM_SELF, quiet=True)
    comm.Barrier()
    two = collapse_verification(out / "particles.h5", scene, comm)
    if comm.Get_rank() == 0:
        one = collapse_verification(out / "particles.h5", scene, MPI.COMM_SELF)
        assert two["collapse"] == one["collapse"]  # the series and plastic work too
        series = one["collapse"]["series"]
        assert {len(v) for v in series.values()} == {3}
        for key in ("plastic_work_J_per_m", "excess_p_max_Pa", "excess_p_p99_Pa"):
            assert key in series, key
        for key in ("plastic_work_J_per_m", "excess_p_peak_Pa", "excess_p_final_Pa",
                    "runout_spread_m", "slide_time_resolution_s"):
            assert key in one["collapse"], key
        a, b = one["pressure_quality"]["series"], two["pressure_quality"]["series"]
        assert a.keys() == b.keys() and len(a["time_s"]) == 3
        for key in a:
            if key.startswith("checkerboard"):  # None where no particle is debris
                assert [v is None for v in b[key]] == [v is None for v in a[key]], key
                assert [v for v in b[key] if v is not None] == pytest.approx(
                    [v for v in a[key] if v is not None], rel=1e-12), key
            else:
                assert b[key] == a[key], key

"""Small particle sets for kernel tests, and a temporary directory shared by MPI ranks."""

import shutil
from pathlib import Path

import numpy as np

from psph.kernels.bundles import PairFields, PairParams, PairRecord, sorted_cells
from psph.kernels.interactions import pair_sums
from psph.kernels.neighbours import cell_lists  # noqa: F401  (tests import it from here)
from psph.kernels.sum_columns import MOMENT, NSUMS


def jittered_lattice(n: int, dx: float, jitter: float, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    g = (np.arange(n) + 0.5) * dx
    x = np.array(np.meshgrid(g, g, indexing="xy")).reshape(2, -1).T
    return x + rng.uniform(-jitter, jitter, x.shape) * dx


def sums_for(x, h, vol, v=None, p=None, stress=None, perm=None, poro=None, rho=None,
             p_prev=None, alpha=0.0, coupled=True, n_owned=None, pairs=None, v_slip=None,
             n_real=None, p_weight=1.0):
    """The pair sums of `interactions.pair_sums` for particles at x; `pairs`: a tuple of
    (int (m, 2), float (m, 2)) arrays that receive the recorded pairs; then the number
    of pairs is returned with the sums."""
    n = len(x)
    z = np.zeros
    v = z((n, 2)) if v is None else v
    v_slip = v if v_slip is None else v_slip
    p = z(n) if p is None else p
    stress = z((n, 4)) if stress is None else stress
    perm = np.ones(n) if perm is None else perm
    poro = np.full(n, 0.4) if poro is None else poro
    rho = np.ones(n) if rho is None else rho
    p_prev = p.copy() if p_prev is None else p_prev
    cell_start, order, ncell = cell_lists(x, h)
    sums = z((n, NSUMS))
    record = pairs if pairs is not None else (np.zeros((0, 2), np.int64), z((0, 2)))
    fields = PairFields(x, v, v_slip, stress, p, p_prev, poro, vol, rho, perm, z((n, 2)),
                        z((n, 3)))
    par = PairParams(h, tpi_alpha=alpha, coupled=coupled, p_weight=p_weight,
                     record=pairs is not None).typed()
    n_pairs = pair_sums(n, n if n_owned is None else n_owned, n if n_real is None else n_real,
                        fields, sorted_cells(cell_start, order, ncell, x), par, sums,
                        PairRecord(*record))
    return sums if pairs is None else (sums, n_pairs)


def inverse_moment(s):
    m = s[:, MOMENT].reshape(-1, 2, 2)
    return np.linalg.inv(m)


def shared_tmp(comm, tmp_path_factory) -> Path:
    """One temporary directory, made by rank 0 and known to every rank."""
    path = str(tmp_path_factory.mktemp("mpi")) if comm.Get_rank() == 0 else None
    return Path(comm.bcast(path, root=0))


SCENES = Path(__file__).resolve().parent / "scenes"  # scene files tests and benches share


def falling_far(tmp: Path) -> Path:
    """A dry block that falls through the whole slab layout: on 2 ranks every particle
    ends below the first cut (migration), and the upper rank runs empty unless the slabs
    are recut (load imbalance)."""
    f = tmp / "falling_far.toml"
    shutil.copyfile(SCENES / "falling_far.toml", f)
    return f


def compare_runs(path_one: Path, path_two: Path, last_only: bool = False):
    """None if two particles.h5 hold bitwise-equal snapshots (by id), else what differs."""
    from psph.io.snapshots import read_snapshots

    one = read_snapshots(path_one)
    two = read_snapshots(path_two)
    if last_only:
        one, two = one[-1:], two[-1:]
    if [s["step"] for s in one] != [s["step"] for s in two]:
        return (f"different snapshot steps {[s['step'] for s in one]} "
                f"vs {[s['step'] for s in two]}")
    for a, b in zip(one, two, strict=True):
        if not np.array_equal(a["id"], b["id"]):  # every particle exactly once
            return f"ids differ at step {a['step']}"
        for field in ("x", "u", "v", "p", "n", "stress", "eps_p", "plastic_work", "material"):
            if field in a and field in b and not np.array_equal(a[field], b[field]):
                diff = np.max(np.abs(a[field] - b[field]))
                return f"{field} differs at step {a['step']} (max abs diff {diff:.3e})"
    return None


def assert_bad_input(result, words, out: Path | None = None) -> None:
    """Bad input as the project promises it: exit 2, one line on stderr naming every
    word of `words` (key, value, rule), no traceback, and nothing written at `out`."""
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])
    assert "Traceback" not in result.stderr
    if out is not None:
        assert not out.exists()

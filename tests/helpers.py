"""Small particle sets for kernel tests, and a temporary directory shared by MPI ranks."""

from pathlib import Path

import numpy as np

from psph.kernels.interactions import NSUMS, pair_sums
from psph.kernels.neighbours import bin_particles, grid_bounds


def jittered_lattice(n: int, dx: float, jitter: float, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    g = (np.arange(n) + 0.5) * dx
    x = np.array(np.meshgrid(g, g, indexing="xy")).reshape(2, -1).T
    return x + rng.uniform(-jitter, jitter, x.shape) * dx


def cell_lists(x: np.ndarray, h: float, key=None):
    n = len(x)
    key = np.arange(n, dtype=float) if key is None else key
    cs = 2 * h
    origin = x.min(axis=0) - 4 * cs
    lo = np.zeros(2, np.int64)
    ncell = np.zeros(2, np.int64)
    grid_bounds(x, n, origin, cs, np.array([1 << 40, 1 << 40], np.int64), lo, ncell)
    nc = int(ncell.prod())
    cell_start = np.zeros(nc + 1, np.int64)
    fill = np.zeros(nc + 1, np.int64)
    cell_of = np.zeros(n, np.int64)
    order = np.zeros(n, np.int64)
    bin_particles(x, key, n, origin, cs, lo, ncell, cell_of, cell_start, fill, order)
    return cell_start, order, ncell


def sums_for(x, h, vol, v=None, p=None, stress=None, perm=None, poro=None, rho=None,
             p_prev=None, alpha=0.0, coupled=True, n_owned=None):
    n = len(x)
    z = np.zeros
    v = z((n, 2)) if v is None else v
    p = z(n) if p is None else p
    stress = z((n, 4)) if stress is None else stress
    perm = np.ones(n) if perm is None else perm
    poro = np.full(n, 0.4) if poro is None else poro
    rho = np.ones(n) if rho is None else rho
    p_prev = p.copy() if p_prev is None else p_prev
    cell_start, order, ncell = cell_lists(x, h)
    sums = z((n, NSUMS))
    pair_sums(n, n if n_owned is None else n_owned, x, v, stress, p, p_prev, poro, vol, rho,
              perm, z((n, 2)), cell_start, order, ncell, h, alpha, 0.0, 0.0, 1.0, 0.0, 0.0,
              coupled, False, sums)
    return sums


def inverse_moment(s):
    m = s[:, 0:4].reshape(-1, 2, 2)
    return np.linalg.inv(m)


def shared_tmp(comm, tmp_path_factory) -> Path:
    """One temporary directory, made by rank 0 and known to every rank."""
    path = str(tmp_path_factory.mktemp("mpi")) if comm.Get_rank() == 0 else None
    return Path(comm.bcast(path, root=0))

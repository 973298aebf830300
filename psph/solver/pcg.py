"""Matrix-free, Jacobi-preconditioned conjugate gradients over the owned particles
(issue 14: the pressure solve of a projection scheme).

The operator, its diagonal and the halo refresh are passed in, so this module knows no
equation and no communicator: `apply(q, out)` writes S q on the owned rows, `refresh(q)`
brings the halo (and wall-ghost) rows of a search direction up to date, and
`dots((a, b), ...)` gives collective, partition-independent inner products over the owned
rows, several in one collective (the exact sums of `psph.kernels.exact_sum`; two
collectives an iteration). With all three reproducible, the iterates, the iteration count
and the solution are the same bits on any rank count.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from psph.kernels.laplacian import cg_step


@dataclass
class PCGWork:
    """Scratch vectors of length `cap` (grown, never per iteration)."""
    cap: int = 0
    r: np.ndarray = field(default_factory=lambda: np.zeros(0))
    z: np.ndarray = field(default_factory=lambda: np.zeros(0))
    d: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sd: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def ensure(self, cap: int) -> None:
        if cap > self.cap:
            self.cap = cap
            self.r, self.z, self.d, self.sd = (np.zeros(cap) for _ in range(4))


@dataclass
class PCGResult:
    iterations: int
    residual: float  # ||rhs - S x|| / ||rhs|| (2-norms over the owned rows)
    converged: bool


def pcg(apply: Callable[[np.ndarray, np.ndarray], None], diag: np.ndarray, rhs: np.ndarray,
        x: np.ndarray, n_owned: int, dots: Callable[..., list[float]],
        refresh: Callable[[np.ndarray], None], tol: float, maxiter: int,
        work: PCGWork) -> PCGResult:
    """Solve S x = rhs for the owned rows of x (its initial value is the first guess; its
    halo rows must be current). Stops when ||r|| <= tol ||rhs||. Collective: every rank
    calls `dots` and `refresh` in the same order. The same iterates as
    `kernels/pcg_serial.py`, whose dot products are evaluated one at a time: exact sums do
    not depend on when they are taken. On return the halo rows of x are not
    refreshed."""
    n = n_owned
    work.ensure(x.shape[0])
    r, z, d, sd = work.r, work.z, work.d, work.sd
    apply(x, sd)
    np.subtract(rhs[:n], sd[:n], out=r[:n])
    np.divide(r[:n], diag[:n], out=z[:n])
    bb, rr, rz = dots((rhs, rhs), (r, r), (r, z))
    b_norm = math.sqrt(bb)
    if b_norm == 0.0:
        b_norm = 1.0
    res = math.sqrt(rr) / b_norm
    if res <= tol:
        return PCGResult(0, res, True)
    d[:n] = z[:n]
    for it in range(1, maxiter + 1):
        refresh(d)
        apply(d, sd)
        (dsd,) = dots((d, sd))
        if not (dsd > 0.0 and math.isfinite(dsd)):
            return PCGResult(it, math.nan if not math.isfinite(dsd) else res, False)
        alpha = rz / dsd
        cg_step(n, alpha, d, sd, x, r)
        np.divide(r[:n], diag[:n], out=z[:n])
        rr, rz_new = dots((r, r), (r, z))
        res = math.sqrt(rr) / b_norm
        if res <= tol:
            return PCGResult(it, res, True)
        if rz == 0.0:  # breakdown (a non-positive preconditioner): not converged
            return PCGResult(it, res, False)
        beta = rz_new / rz
        rz = rz_new
        d[:n] *= beta
        d[:n] += z[:n]
    return PCGResult(maxiter, res, False)

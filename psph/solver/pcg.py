"""Matrix-free, Jacobi-preconditioned conjugate gradients over the owned particles
(the pressure solve of the projection scheme).

The operator, its diagonal and the halo refresh are passed in, so this module knows no
equation and no communicator: `apply(q, out)` writes S q on the owned rows, `refresh(q)`
brings the halo (and wall-ghost) rows of a search direction up to date, and
`dots((a, b), ...)` gives collective, partition-independent inner products over the owned
rows, several in one collective (the exact sums of `psph.kernels.exact_sum`). With all
three reproducible, the iterates, the iteration count and the solution are the same bits
on any rank count.

The recurrences are Chronopoulos and Gear's (1989, "s-step iterative methods for symmetric
linear systems", J. Comput. Appl. Math. 25): the same iterates as Hestenes-Stiefel CG in
exact arithmetic, but the three inner products of an iteration, (r, r), (r, u) and
(S u, u) with u the preconditioned residual, are taken at one point, so an iteration is
one halo refresh and one collective (it was two collectives), and S d follows from
S u by the recurrence S d = S u + beta S d.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from psph.kernels.laplacian import cg_advance, jacobi


@dataclass
class PCGWork:
    """Scratch vectors of length `cap` (grown, never per iteration): the residual r, the
    preconditioned residual u, its image w = S u, the search direction d and its image sd."""
    cap: int = 0
    r: np.ndarray = field(default_factory=lambda: np.zeros(0))
    u: np.ndarray = field(default_factory=lambda: np.zeros(0))
    w: np.ndarray = field(default_factory=lambda: np.zeros(0))
    d: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sd: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def ensure(self, cap: int) -> None:
        if cap > self.cap:
            self.cap = cap
            self.r, self.u, self.w, self.d, self.sd = (np.zeros(cap) for _ in range(5))


@dataclass
class PCGResult:
    iterations: int
    residual: float  # ||rhs - S x|| / ||rhs|| (2-norms over the owned rows)
    converged: bool


def pcg(apply: Callable[[np.ndarray, np.ndarray], None], diag: np.ndarray, rhs: np.ndarray,
        x: np.ndarray, n_owned: int, dots: Callable[..., list[float]],
        refresh: Callable[[np.ndarray], None], tol: float, maxiter: int,
        work: PCGWork, r0_out: np.ndarray | None = None) -> PCGResult:
    """Solve S x = rhs for the owned rows of x (its initial value is the first guess; its
    halo rows must be current). Stops when ||r|| <= tol ||rhs||. Collective: every rank
    calls `dots` and `refresh` in the same order. The same iterates as
    `kernels/pcg_serial.py`, whose dot products are evaluated one at a time: exact sums do
    not depend on when they are taken. On return the halo rows of x are not
    refreshed; work.r holds the last residual (of the recurrences), and `r0_out`,
    if given, the first (rhs - S x on entry)."""
    n = n_owned
    work.ensure(x.shape[0])
    r, u, w, d, sd = work.r, work.u, work.w, work.d, work.sd
    apply(x, w)
    np.subtract(rhs[:n], w[:n], out=r[:n])
    if r0_out is not None:
        r0_out[:n] = r[:n]
    jacobi(n, r, diag, u)
    refresh(u)
    apply(u, w)
    bb, rr, ru, wu = dots((rhs, rhs), (r, r), (r, u), (w, u))
    b_norm = math.sqrt(bb)
    if b_norm == 0.0:
        b_norm = 1.0
    res = math.sqrt(rr) / b_norm
    if res <= tol:
        return PCGResult(0, res, True)
    d_sd = wu  # (d, S d) with d = u
    beta = 0.0
    for it in range(1, maxiter + 1):
        if not (d_sd > 0.0 and math.isfinite(d_sd)):
            return PCGResult(it, math.nan if not math.isfinite(d_sd) else res, False)
        alpha = ru / d_sd
        cg_advance(n, alpha, beta, u, w, d, sd, x, r, diag)
        refresh(u)
        apply(u, w)
        rr, ru_new, wu = dots((r, r), (r, u), (w, u))
        res = math.sqrt(rr) / b_norm
        if res <= tol:
            return PCGResult(it, res, True)
        if ru == 0.0:  # breakdown (a non-positive preconditioner): not converged
            return PCGResult(it, res, False)
        beta = ru_new / ru
        d_sd = wu - beta * ru_new / alpha  # (d, S d) of the next direction
        ru = ru_new
    return PCGResult(maxiter, res, False)

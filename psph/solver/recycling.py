"""A recycled initial guess for the projection's pressure solve: Fischer's
projection onto earlier solutions (P. F. Fischer 1998, "Projection techniques for
iterative solution of Ax = b with successive right-hand sides", Comput. Methods Appl.
Mech. Eng. 163), on top of the extrapolated warm start.

The basis X holds up to L = `pressure.recycle` earlier CG corrections (the solution minus
its initial guess), S-orthonormalised when they were added, with their images S X. A step's
guess is the extrapolation x_e plus the S-projection of its error onto X:
x_0 = x_e + X X^T (b - S x_e) (one operator apply); the correction's image S e is the
difference of the solve's first and last residuals (no apply). When the basis is
full it restarts from the latest solution alone (Fischer's restart). X and S X are
particle fields (`recycle_x`, `recycle_sx`): they move with their particles between ranks
and go into checkpoints, so the guesses, the iteration counts and the solution are the
same bits on any number of ranks and after a restart. Their inner products are
`kernels/recycling.rounded_dots`.

Why: on the paper's Section 4.1 column (the default run, L = 64) it takes 0.61 CG
iterations a step instead of 8.97, with the same p to 1e-8 of q.
"""

import math

import numpy as np

from psph.kernels.recycling import (
    combine,
    max_abs_products,
    orthogonalise,
    rounded_dots,
    store_column,
)


class RecycledGuess:
    """The basis' bookkeeping on this rank: how many columns are in use (the same on every
    rank) and the drained planes' state they were built under (a switch of the planes
    changes the operator: the basis starts again)."""

    def __init__(self, size: int):
        self.size = size
        self.k = 0
        self.planes: tuple = ()
        self._x0 = np.zeros(0)
        self._e = np.zeros(0)
        self._se = np.zeros(0)
        self.r0 = np.zeros(0)  # the solve's first residual (`pcg`'s r0_out)
        self._free = np.zeros(0, np.bool_)
        self._ints = np.zeros(size + 1, np.int64)
        self._total = np.zeros(size + 1, np.int64)
        self.resets = 0

    def state(self) -> dict:
        return {"size": self.size, "k": self.k, "planes": list(self.planes)}

    def restore(self, state: dict | None) -> None:
        """The basis' state of a checkpoint, when its size is this run's (else the
        checkpoint's basis was not loaded and the guess starts anew)."""
        if state and state["size"] == self.size:
            self.k = int(state["k"])
            self.planes = tuple(state["planes"])

    def _scratch(self, cap: int) -> None:
        if self._e.shape[0] < cap:
            self._x0, self._e, self._se, self.r0 = (np.zeros(cap) for _ in range(4))
            self._free = np.zeros(cap, np.bool_)

    def free_rows(self, fixed: np.ndarray, n: int, cap: int) -> np.ndarray:
        """The owned rows that are not imposed (no allocation per step)."""
        self._scratch(cap)
        return np.logical_not(fixed[:n], out=self._free[:n])

    def _reduce(self, slabs, m: float, n_global: int, fill) -> float | None:
        """The scale of the rounded terms from the largest one over all ranks (m, this
        rank's), `fill(scale)` writing this rank's integer sums into self._ints, and the
        sums over all ranks into self._total; None if every term is 0 or one is not
        finite. Two collectives."""
        m = slabs.allreduce_max(m)
        if not (m > 0.0 and math.isfinite(m)):
            return None
        _, e = math.frexp(m * max(n_global, 1))
        scale = math.ldexp(1.0, 62 - e)  # every rank's sum of terms stays below 2^62
        fill(scale)
        return scale

    def _dots(self, slabs, n: int, basis: np.ndarray, k: int, r: np.ndarray,
              free: np.ndarray, n_global: int) -> np.ndarray:
        """basis[:, :k]^T r over the free owned rows of every rank, the same bits on any
        partition."""
        scale = self._reduce(slabs, max_abs_products(n, basis, k, r, free), n_global,
                             lambda sc: rounded_dots(n, basis, k, r, free, sc, self._ints))
        if scale is None:
            return np.zeros(k)
        slabs.allreduce_sum(self._ints[:k], self._total[:k])
        return self._total[:k] / scale

    def guess(self, sim, basis, rhs, d, free, apply, refresh) -> None:
        """Add to the extrapolated guess d (owned rows; imposed rows at their values) its
        S-projected error on the basis, X X^T (b - S d): one apply of this step's operator
        (the stored images S X are of older operators, and X^T b - (S X)^T d cancels to
        1e-3 of its terms: their drift ruined the guess). Collective."""
        st = sim.store
        n = st.n_owned
        self._scratch(st.cap)
        k = self.k
        if k > 0:
            x = basis[0]
            refresh(d)
            r = self._e
            apply(d, r)
            np.subtract(rhs[:n], r[:n], out=r[:n])
            combine(n, x, k, self._dots(sim.slabs, n, x, k, r, free, sim.n_global), free, d)
        self._x0[:n] = d[:n]

    def start(self, planes: tuple) -> None:
        """Drop the basis when the drained planes switch (the operator changes)."""
        if planes != self.planes:
            self.planes = planes
            self.resets += self.k > 0
            self.k = 0

    def update(self, sim, basis, d, free, rhs, r0, r) -> None:
        """Add this step's correction e = d - x_0 to the basis with its image S e = r0 - r
        (the solve's first and last residuals; no apply), S-orthonormalised; when the
        basis is full, the solution d alone, S d = b - r (Fischer's restart).
        Collective."""
        if self.size == 0:
            return
        st = sim.store
        n = st.n_owned
        x, sx = basis
        e, se = self._e, self._se
        if self.k >= self.size:
            self.k = 0
            e[:n] = d[:n]
            np.subtract(rhs[:n], r[:n], out=se[:n])
        else:
            np.subtract(d[:n], self._x0[:n], out=e[:n])
            np.subtract(r0[:n], r[:n], out=se[:n])
        k = self.k
        x[:n, k] = e[:n]  # the new column, to take e.Se with the h_j = x_j.Se
        dots = self._dots(sim.slabs, n, x, k + 1, se, free, sim.n_global)
        h, norm0 = dots[:k], dots[k]
        if not norm0 > 0.0:
            return
        orthogonalise(n, x, sx, k, h, free, e, se)
        norm = norm0 - float(h @ h)  # Pythagoras in the (nearly) S-orthonormal basis
        if norm <= 0.25 * norm0:  # cancellation: the norm itself
            x[:n, k] = e[:n]
            norm = self._dots(sim.slabs, n, x, k + 1, se, free, sim.n_global)[k]
        if not norm > 1e-24 * norm0:
            return
        store_column(n, x, sx, k, e, se, 1.0 / math.sqrt(norm))
        self.k = k + 1

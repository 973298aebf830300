"""Inner products over the owned rows with the same bits on any rank count, several in
one collective: each rank's terms as integer chunk rows (`kernels/exact_sum.dot_chunks`),
summed by one integer Allreduce, read back as the correctly rounded exact sums
(`chunks_value`). A term the chunks cannot hold (huge or not finite, on any rank) falls
back to gathering the ranks' expansions, which gives the same values. Used by the CG of
the projection on several ranks and by the drained planes' mean displacement."""

import numpy as np

from psph.kernels.exact_sum import (
    BLOCK,
    CHUNK_ROW,
    CHUNKS,
    EXPANSION_CAP,
    chunk_row_values,
    dot_chunk_rows,
    dot_expansion,
    local_parts,
)


class ExactDots:
    """Scratch of the reductions (grown to the most pairs a call takes, never per call)."""

    def __init__(self) -> None:
        self._rows = np.zeros((0, CHUNK_ROW), np.int64)
        self._rows_sum = np.zeros((0, CHUNK_ROW), np.int64)
        self._terms = np.zeros(BLOCK)
        self._acc = np.zeros(CHUNKS, np.int64)
        self._buf = np.zeros(EXPANSION_CAP)
        self._bufs: list[np.ndarray] = []
        self._values = np.zeros(0)

    def __call__(self, slabs, n: int, *pairs: tuple[np.ndarray, np.ndarray]) -> list[float]:
        """sum_k a[k] b[k] over k < n for each pair (a, b), correctly rounded, over all
        ranks of `slabs` (collective: every rank passes the same number of pairs). The
        arrays: 1-D float64, C-contiguous and writeable, all of one numba type (one
        compiled call takes them as a tuple)."""
        k = len(pairs)
        if k == 0:
            return []
        if self._rows.shape[0] < k:
            self._rows = np.zeros((k, CHUNK_ROW), np.int64)
            self._rows_sum = np.zeros((k, CHUNK_ROW), np.int64)
        rows, total = self._rows[:k], self._rows_sum[:k]
        if self._values.shape[0] < k:
            self._values = np.zeros(k)
        values = self._values[:k]
        # one compiled call for all the rows (a CG iteration on several ranks is
        # latency-bound)
        a = tuple(p[0] for p in pairs)
        b = tuple(p[1] for p in pairs)
        dot_chunk_rows(a, b, n, rows, self._terms)
        slabs.allreduce_sum(rows, total)
        if chunk_row_values(total, self._buf, self._acc, values):
            return values.tolist()
        if len(self._bufs) < k:
            self._bufs = [np.zeros(EXPANSION_CAP) for _ in pairs]
        parts = [local_parts(buf, dot_expansion(x, y, n, buf))
                 for (x, y), buf in zip(pairs, self._bufs, strict=False)]
        return slabs.exact_sums(parts)

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
    SPECIAL,
    chunks_value,
    dot_chunks,
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

    def __call__(self, slabs, n: int, *pairs: tuple[np.ndarray, np.ndarray]) -> list[float]:
        """sum_k a[k] b[k] over k < n for each pair (a, b), correctly rounded, over all
        ranks of `slabs` (collective: every rank passes the same number of pairs)."""
        k = len(pairs)
        if self._rows.shape[0] < k:
            self._rows = np.zeros((k, CHUNK_ROW), np.int64)
            self._rows_sum = np.zeros((k, CHUNK_ROW), np.int64)
        rows, total = self._rows[:k], self._rows_sum[:k]
        for row, (a, b) in zip(rows, pairs, strict=True):
            dot_chunks(a, b, n, row, self._terms)
        slabs.allreduce_sum(rows, total)
        if total[:, SPECIAL].any():
            if len(self._bufs) < k:
                self._bufs = [np.zeros(EXPANSION_CAP) for _ in pairs]
            parts = [local_parts(buf, dot_expansion(a, b, n, buf))
                     for (a, b), buf in zip(pairs, self._bufs, strict=False)]
            return slabs.exact_sums(parts)
        return [chunks_value(row, self._buf, self._acc) for row in total]

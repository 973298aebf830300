"""The non-local softening variable of a set of particles, offline: the solver's kernel
(`psph/kernels/nonlocal_strain.py`) with its cell lists built once, for one or more
weight sets m (m = 1: the plain average eps_bar; the material's m: eps_hat).

Used by the regularisation tests and by the studies that look into a band
(`bench/studies/nonlocal_wall_band.py`).
"""

from collections.abc import Sequence

import numpy as np

from psph.kernels.bundles import CellList, NonlocalFields
from psph.kernels.neighbours import cell_lists_indexed
from psph.kernels.nonlocal_strain import nonlocal_strain, nonlocal_strain_3d, rings_for


def nonlocal_strains(x: np.ndarray, vol: np.ndarray, eps_p: np.ndarray,
                     lengths: Sequence[float], weight_sets: Sequence[Sequence[float]], *,
                     material: np.ndarray | None = None, n_owned: int | None = None,
                     walls: Sequence[tuple[int, float]] = (),
                     h: float | None = None) -> list[np.ndarray]:
    """eps_hat of rows 0..n_owned-1 (default: every row; the rest NaN) for each weight
    set (m per material), all rows real. lengths[k]: l_c of material k (0: local);
    walls: (axis, position) planes whose images enter; h: half the cell side (default
    l_c / 4: any size works, the kernel searches the rings that cover 2 l_c). x: (N, 2)
    or (N, 3)."""
    n = len(x)
    x = np.ascontiguousarray(x, float)
    material = np.zeros(n) if material is None else np.ascontiguousarray(material, float)
    lengths = np.asarray(lengths, float)
    if material.size and material.max() >= len(lengths):
        raise ValueError("material index beyond the lengths table")  # the kernel reads it
    owned = n if n_owned is None else n_owned
    if float(lengths.max(initial=0.0)) <= 0.0:  # every material local: eps_hat = eps_p
        local = np.full(n, np.nan)
        local[:owned] = np.asarray(eps_p, float)[:owned]
        return [local.copy() for _ in weight_sets]
    h = 0.25 * float(lengths.max()) if h is None else h
    cells = CellList(*cell_lists_indexed(x, h))
    rings = rings_for(float(lengths.max()), 2 * h)
    scratch = np.zeros(int(np.prod(cells.ncell)), np.int8)
    average = nonlocal_strain if x.shape[1] == 2 else nonlocal_strain_3d
    axis = np.array([a for a, _ in walls], np.int64)
    pos = np.array([p for _, p in walls], float)
    fields = NonlocalFields(x, np.ascontiguousarray(vol, float),
                            np.ascontiguousarray(eps_p, float), material)
    out = []
    for weights in weight_sets:
        hat = np.full(n, np.nan)
        average(owned, n, fields, lengths, np.asarray(weights, float), cells, rings, scratch,
                axis, pos, hat)
        out.append(hat)
    return out

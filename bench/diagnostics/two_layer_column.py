"""The two-layer column at rest under gravity of `tests/test_materials.py` (its scene file
`tests/scenes/two_layers.toml` and the same odd-even filter), for `oddeven_stress_mode.py`."""

from pathlib import Path

import numpy as np

LAYERED = (Path(__file__).resolve().parents[2] / "tests" / "scenes" / "two_layers.toml").read_text()


def row_pairs(a, x0, y0):
    """Mean of each particle and the one below it in its lattice column: takes out the
    odd-even (zig-zag) mode of sigma' on the lattice (README, issue 13)."""
    order = np.lexsort((y0, np.round(x0, 9)))
    b = a[order]
    same = np.isclose(x0[order][1:], x0[order][:-1])
    return 0.5 * (b[1:] + b[:-1])[same]

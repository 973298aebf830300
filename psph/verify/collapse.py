"""Metrics of a collapse or slope failure from the particle positions (Sections 4.4-4.5):
run-out distance, final height and back-scarp position."""

import numpy as np


def collapse_metrics(x: np.ndarray, x0: np.ndarray, dx: float) -> dict:
    """x, x0: (N, 2) current and initial positions of all particles.

    - runout_m: how far the toe advanced: the 99.8th percentile of x (a few splashed
      particles do not count) minus the initial largest x;
    - toe_m: that percentile itself;
    - final_height_m / initial_height_m: the highest particle within 5 dx of the left
      end of the mass;
    - back_scarp_m: the smallest x where the free surface lies below 95 % of the initial
      height (the crest of the failure), measured in columns of width 2 dx.
    """
    toe = float(np.percentile(x[:, 0], 99.8))
    left = x0[:, 0].min()
    h0 = float(x0[:, 1].max() + 0.5 * dx)
    near = x[:, 0] < left + 5 * dx
    height = float(x[near, 1].max() + 0.5 * dx) if near.any() else 0.0
    col = np.floor((x[:, 0] - left) / (2 * dx)).astype(int)
    col = np.clip(col, 0, None)
    top = np.full(col.max() + 1, -np.inf)
    np.maximum.at(top, col, x[:, 1] + 0.5 * dx)
    low = np.flatnonzero(top < 0.95 * h0)
    scarp = float(left + 2 * dx * low[0]) if len(low) else float(x[:, 0].max())
    return {"runout_m": toe - float(x0[:, 0].max()), "toe_m": toe,
            "initial_height_m": h0, "final_height_m": height, "back_scarp_m": scarp}

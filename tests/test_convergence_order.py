"""Observed order and Richardson extrapolation (psph/verify/convergence.py), used by
bench/verification/convergence.py (issue 17): exact on a metric that converges as a power of the
spacing, no order where the differences change sign."""

import math

import pytest

from psph.verify.convergence import richardson, series


@pytest.mark.parametrize("order", [1.0, 2.0, 0.7])
def test_power_law_metric_gives_its_order_and_limit(order):
    r = math.sqrt(2.0)
    dx = [0.04, 0.04 / r, 0.02]
    f = [3.5 + 12.0 * d ** order for d in dx]
    out = richardson(f, r)
    assert out["order"] == pytest.approx(order, rel=1e-9)
    assert out["extrapolated"] == pytest.approx(3.5, rel=1e-9)


def test_oscillating_or_flat_series_has_no_order():
    assert richardson([1.0, 1.2, 1.1], 2.0) == {"order": None, "extrapolated": None}
    assert richardson([1.0, 1.0, 1.0], 2.0)["extrapolated"] is None
    diverging = richardson([1.0, 1.1, 1.3], 2.0)  # differences grow: no limit
    assert diverging["order"] < 0 and diverging["extrapolated"] is None


def test_series_over_dx_and_dt():
    """Three spacings at one dt fraction give a dx series; three fractions at one dx a
    dt series; a group with two points gives none."""
    r = math.sqrt(2.0)
    rows = []
    for dx in (0.04, 0.04 / r, 0.02):
        for f in (1.0, 0.5, 0.25):
            rows.append({"scene": "s", "scheme": "tpi", "law": "local", "dx": dx,
                         "dt_fraction": f, "runout_m": 2.0 + dx ** 2 + 1e-3 * f})
    rows.append({"scene": "s", "scheme": "tpi", "law": "regularised", "dx": 0.04,
                 "dt_fraction": 1.0, "runout_m": 2.0})
    out = series(rows)
    in_dx = [s for s in out if s["in"] == "dx"]
    in_dt = [s for s in out if s["in"] == "dt"]
    assert len(in_dx) == 3 and len(in_dt) == 3
    assert all(s["law"] == "local" for s in out)
    assert all(s["order"] == pytest.approx(2.0, rel=1e-6) for s in in_dx)
    assert all(s["order"] == pytest.approx(1.0, rel=1e-6) for s in in_dt)

"""Observed order of convergence and Richardson extrapolation of a metric over three
refinements (`bench/verification/convergence.py`). With f1, f2, f3 the values at the
coarse, middle and fine resolution and a constant ratio r between them,

    p = ln((f1 - f2) / (f2 - f3)) / ln r,    f* = f3 + (f3 - f2) / (r^p - 1)

(Roache's grid-convergence form), defined only when the two differences keep one sign.
"""

import math


def richardson(f: list[float], r: float) -> dict:
    """Observed order and extrapolated value of three values f (coarse to fine) at the
    constant refinement ratio r; {"order": None, ...} when the differences change sign
    or vanish (no asymptotic range to extrapolate from)."""
    d1, d2 = f[0] - f[1], f[1] - f[2]
    if d1 == 0.0 or d2 == 0.0 or (d1 > 0.0) != (d2 > 0.0):
        return {"order": None, "extrapolated": None}
    p = math.log(d1 / d2) / math.log(r)
    if not p > 0.0:  # diverging differences: no limit to extrapolate to
        return {"order": p, "extrapolated": None}
    return {"order": p, "extrapolated": f[2] + (f[2] - f[1]) / (r ** p - 1.0)}


def _entry(key: tuple, axis: str, at: str, rows: list[dict], metric: str, r: float) -> dict:
    """One series of three runs (coarse to fine) with its order and extrapolation."""
    vals = [e[metric] for e in rows]
    change = abs(vals[2] - vals[1]) / abs(vals[2]) if vals[2] else None
    return {"scene": key[0], "scheme": key[1], "law": key[2], "in": axis, "at": at,
            "values": vals, "finest_change": change, **richardson(vals, r)}


def series(report: list[dict], metric: str = "runout_m") -> list[dict]:
    """Richardson over dx (r = sqrt 2) for every scene, scheme, law and dt fraction with
    three spacings measured, and over dt (r = 2) for every dx with three fractions."""
    done = [e for e in report if metric in e]
    out = []
    for key in sorted({(e["scene"], e["scheme"], e["law"]) for e in done}):
        group = [e for e in done if (e["scene"], e["scheme"], e["law"]) == key]
        for f in sorted({e["dt_fraction"] for e in group}, reverse=True):
            row = sorted((e for e in group if e["dt_fraction"] == f), key=lambda e: -e["dx"])
            if len(row) == 3:
                out.append(_entry(key, "dx", f"dt={f:g}", row, metric, math.sqrt(2.0)))
        for dx in sorted({e["dx"] for e in group}, reverse=True):
            col = sorted((e for e in group if e["dx"] == dx), key=lambda e: -e["dt_fraction"])
            if len(col) == 3:
                out.append(_entry(key, "dt", f"dx={dx:.4g}", col, metric, 2.0))
    return out

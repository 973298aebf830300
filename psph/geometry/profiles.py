"""Ground profiles of a cross-section: a polyline z(x) given inline as [x, z]
points or as a CSV file of x, z rows (the way survey sections come), and the soil layer
between a top and a bottom profile.

A profile is strictly increasing in x; between its points it is linear, outside its x
range it does not exist. A layer holds the lattice points with bottom(x) <= z <= top(x)
where both profiles exist.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from psph.errors import SceneRule


class ProfileError(ValueError):
    """A profile that cannot be used: `where` (an index, a row or an x) and the rule."""

    def __init__(self, where: str, value, rule: str):
        super().__init__(f"{where}: {rule}")
        self.where, self.value, self.rule = where, value, rule


def read_profile(value: list | str, axis: int = 0) -> np.ndarray:
    """(k, 2) points of a profile given as [[x, z], ...] or as the path of a CSV file
    with one x, z pair per row (a header row and `#` comments are skipped). The
    coordinate `axis` (0: x, 1: z, for a wall x(z)) must increase strictly."""
    if isinstance(value, str):
        path = Path(value)
        if not path.is_file():
            raise ProfileError("file", value, "no such file")
        rows = []
        for n, line in enumerate(path.read_text().splitlines(), start=1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            cells = [c.strip() for c in text.replace(";", ",").split(",")]
            try:
                xz = [float(c) for c in cells]
            except ValueError:
                if not rows:  # a header
                    continue
                raise ProfileError(f"{value} line {n}", line, "not two numbers x, z") \
                    from None
            if len(xz) != 2:
                raise ProfileError(f"{value} line {n}", line, "not two numbers x, z")
            rows.append(xz)
        points = np.array(rows, float).reshape(-1, 2)
    else:
        points = np.asarray(value, float).reshape(-1, 2)
    if len(points) < 2:
        raise ProfileError("points", len(points), "a profile needs at least 2 points")
    if not np.all(np.isfinite(points)):
        raise ProfileError("points", "non-finite", "coordinates must be finite")
    bad = np.flatnonzero(np.diff(points[:, axis]) <= 0.0)
    if len(bad):
        i = int(bad[0]) + 1
        c = "xz"[axis]
        raise ProfileError(f"point {i}", points[i].tolist(),
                           f"{c} must increase along the profile ({c} = {points[i, axis]:g} "
                           f"after {points[i - 1, axis]:g}): not monotonic in {c}")
    return points


def check_layer(top: np.ndarray, bottom: np.ndarray) -> None:
    """The two profiles share an x range and the bottom is nowhere above the top there
    (checked at every point of either profile)."""
    x0, x1 = max(top[0, 0], bottom[0, 0]), min(top[-1, 0], bottom[-1, 0])
    if x1 <= x0:
        raise ProfileError("bottom", [bottom[0, 0], bottom[-1, 0]],
                           f"no x range in common with the top ([{top[0, 0]:g}, "
                           f"{top[-1, 0]:g}])")
    xs = np.unique(np.concatenate([top[:, 0], bottom[:, 0]]))
    xs = xs[(xs >= x0) & (xs <= x1)]
    gap = np.interp(xs, top[:, 0], top[:, 1]) - np.interp(xs, bottom[:, 0], bottom[:, 1])
    scale = max(np.ptp(top[:, 1]), np.ptp(bottom[:, 1]), 1.0)
    if np.any(gap < -1e-9 * scale):
        i = int(np.argmin(gap))
        raise ProfileError("bottom", float(xs[i]),
                           f"above the top at x = {xs[i]:g} (by {-gap[i]:g} m)")


def inside_layer(points: np.ndarray, top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
    """Mask of the points between the profiles: bottom(x) <= z <= top(x) (to a relative
    1e-9, as `inside_polygon` counts edges), within both profiles' x range."""
    x, z = points[:, 0], points[:, 1]
    eps = 1e-9 * max(np.ptp(np.concatenate([top, bottom]), axis=0).max(), 1.0)
    x0, x1 = max(top[0, 0], bottom[0, 0]), min(top[-1, 0], bottom[-1, 0])
    within = (x >= x0 - eps) & (x <= x1 + eps)
    zt = np.interp(x, top[:, 0], top[:, 1])
    zb = np.interp(x, bottom[:, 0], bottom[:, 1])
    return within & (z >= zb - eps) & (z <= zt + eps)


def check_water_table(table: float | list | str, lo, hi) -> None:
    """`initial.water_table` as a level or a profile (`read_profile`) over the domain
    [lo, hi]: a profile shares its x range, and neither dips below the domain's floor
    wherever it is over the domain (at the profile's points there and at the domain's
    sides). Above the top is allowed: ponded or submerged ground."""
    if isinstance(table, (int, float)):
        if table < lo[1]:
            raise ProfileError("level", table, f"below the domain's floor y = {lo[1]:g} m")
        return
    points = read_profile(table)
    x0, x1 = max(points[0, 0], lo[0]), min(points[-1, 0], hi[0])
    if x1 < x0:
        raise ProfileError("points", [points[0, 0], points[-1, 0]],
                           f"no x in the domain's [{lo[0]:g}, {hi[0]:g}] m")
    xs = np.concatenate([[x0, x1], points[(points[:, 0] > x0) & (points[:, 0] < x1), 0]])
    z = np.interp(xs, points[:, 0], points[:, 1])
    out = np.flatnonzero(z < lo[1])
    if len(out):
        i = int(out[0])
        raise ProfileError(f"at x = {xs[i]:g}", float(z[i]),
                           f"below the domain's floor y = {lo[1]:g} m")


def check_layer_profiles(layer, key: str):
    """`layer` (a `[[particles.layers]]` table at `key`): both profiles readable and
    increasing in x, the bottom nowhere above the top; returns their (k, 2) points.
    Raises SceneRule naming the key, the value and the rule."""
    points = {}
    for side in ("top", "bottom"):
        value = getattr(layer, side)
        try:
            points[side] = read_profile(value)
        except ProfileError as e:
            where = f"{key}.{side}" + ("" if e.where in ("points", "file") else f" {e.where}")
            raise SceneRule(where, e.value, e.rule) from None
    try:
        check_layer(points["top"], points["bottom"])
    except ProfileError as e:
        raise SceneRule(f"{key}.bottom", e.value, e.rule) from None
    return points["top"], points["bottom"]


"""Elevation grids of 3D scenes: a ground surface, a layer interface, a bedrock
or a water table as z(x, y) on a regular grid of nodes, the way digital elevation models
and interpolated borehole surfaces come.

Two file formats:

- ESRI ASCII grid (`.asc`): a header of `ncols`, `nrows`, `xllcorner` or `xllcenter`,
  `yllcorner` or `yllcenter`, `cellsize` (or `dx` and `dy`) and an optional
  `NODATA_value`, then `nrows` rows of `ncols` elevations, the first row the northern
  (largest y). A value is the elevation at its cell's centre: with `xllcorner` the first
  centre is half a cell in from the corner, with `xllcenter` it is the given point.
- a CSV of x, y, z rows (a header row and `#` comments skipped; `,`, `;` or blanks
  between numbers), whose points fill a regular grid: every combination of its distinct
  x and y once, each axis evenly spaced.

Between nodes the surface is bilinear; outside the outermost nodes, and in a cell with a
corner without data (NODATA, NaN), it does not exist (NaN). Errors name the file, the
node or point, and the rule (`GridError`), for the scene rules to report on one line.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np


class GridError(ValueError):
    """A grid that cannot be used: `where` (the file, with a row or a point) and the rule."""

    def __init__(self, where: str, value, rule: str):
        super().__init__(f"{where}: {rule}")
        self.where, self.value, self.rule = where, value, rule


@dataclass(frozen=True)
class ElevationGrid:
    """Nodes x (nx,) and y (ny,), both increasing and evenly spaced, and elevations z
    (ny, nx), NaN where there is no data; `path` names it in messages."""

    path: str
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray

    def at(self, px: np.ndarray, py: np.ndarray) -> np.ndarray:
        """Bilinear elevation at the points (px, py); NaN outside the nodes' range or in a
        cell with a corner without data."""
        px = np.asarray(px, float)
        py = np.asarray(py, float)
        hx = self.x[1] - self.x[0] if len(self.x) > 1 else 1.0
        hy = self.y[1] - self.y[0] if len(self.y) > 1 else 1.0
        eps = 1e-9 * max(hx, hy)
        fx = (px - self.x[0]) / hx
        fy = (py - self.y[0]) / hy
        i = np.clip(np.floor(fx).astype(np.int64), 0, max(len(self.x) - 2, 0))
        j = np.clip(np.floor(fy).astype(np.int64), 0, max(len(self.y) - 2, 0))
        tx = fx - i
        ty = fy - j
        i1 = np.minimum(i + 1, len(self.x) - 1)
        j1 = np.minimum(j + 1, len(self.y) - 1)
        z = np.zeros(np.broadcast(px, py).shape)
        for wt, zc in (((1 - tx) * (1 - ty), self.z[j, i]), (tx * (1 - ty), self.z[j, i1]),
                       ((1 - tx) * ty, self.z[j1, i]), (tx * ty, self.z[j1, i1])):
            # a corner of weight 0 (a point on a node or an edge) does not count, with
            # or without data
            z += np.where(wt > 0.0, wt * np.where(np.isfinite(zc), zc, np.nan), 0.0)
        outside = ((px < self.x[0] - eps) | (px > self.x[-1] + eps)
                   | (py < self.y[0] - eps) | (py > self.y[-1] + eps))
        return np.where(outside, np.nan, z)

    def missing_corner(self, px: float, py: float) -> tuple[float, float]:
        """(x, y) of a node without data among those the surface at (px, py) takes."""
        hx, hy = self.x[1] - self.x[0], self.y[1] - self.y[0]
        i = int(np.clip(np.floor((px - self.x[0]) / hx), 0, len(self.x) - 2))
        j = int(np.clip(np.floor((py - self.y[0]) / hy), 0, len(self.y) - 2))
        for jj in (j, j + 1):
            for ii in (i, i + 1):
                if not np.isfinite(self.z[jj, ii]):
                    return float(self.x[ii]), float(self.y[jj])
        return float(px), float(py)

    def where(self, px: float, py: float) -> str:
        """A node of the grid as its file names it: an ESRI grid's row (from the north,
        from 0) and column, a CSV's x and y."""
        if Path(self.path).suffix.lower() != ".asc":
            return f"x = {px:g}, y = {py:g}"
        row, col = self.file_row_col(px, py)
        return f"row {row}, column {col}"

    def file_row_col(self, px: float, py: float) -> tuple[int, int]:
        """The (row, column) of the node nearest (px, py) as the file counts them: an ESRI
        grid's rows from the north, from 0."""
        col = int(np.clip(np.rint((px - self.x[0]) / (self.x[1] - self.x[0])), 0,
                          len(self.x) - 1)) if len(self.x) > 1 else 0
        row = int(np.clip(np.rint((py - self.y[0]) / (self.y[1] - self.y[0])), 0,
                          len(self.y) - 1)) if len(self.y) > 1 else 0
        return len(self.y) - 1 - row, col


def is_grid_file(value) -> bool:
    """Whether a scene value names an elevation grid: a `.asc` file, or a CSV whose first
    data row has three numbers (a profile's has two)."""
    if not isinstance(value, str):
        return False
    path = Path(value)
    if path.suffix.lower() == ".asc":
        return True
    if not path.is_file():
        return False
    for line in path.read_text().splitlines():
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        cells = text.replace(";", ",").replace(",", " ").split()
        try:
            return len([float(c) for c in cells]) == 3
        except ValueError:
            continue  # a header
    return False


def read_grid(value: str) -> ElevationGrid:
    """The elevation grid of a `.asc` file or an x, y, z CSV (module docstring). Raises
    GridError."""
    path = Path(value)
    if not path.is_file():
        raise GridError(value, value, "no such file")
    if path.suffix.lower() == ".asc":
        return _read_asc(value, path.read_text())
    return _read_xyz(value, path.read_text())


def _read_asc(name: str, text: str) -> ElevationGrid:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    head: dict[str, float] = {}
    k = 0
    while k < len(lines):
        words = lines[k].split()
        if len(words) != 2 or not words[0][0].isalpha():
            break
        try:
            head[words[0].lower()] = float(words[1])
        except ValueError:
            raise GridError(f"{name} line {k + 1}", lines[k], "not a header 'key value'") \
                from None
        k += 1
    for key in ("ncols", "nrows"):
        if key not in head or head[key] < 2 or head[key] != int(head[key]):
            raise GridError(f"{name} header", head.get(key), f"{key} must be an integer >= 2")
    nx, ny = int(head["ncols"]), int(head["nrows"])
    hx = head.get("cellsize", head.get("dx"))
    hy = head.get("cellsize", head.get("dy"))
    if hx is None or hy is None or hx <= 0 or hy <= 0:
        raise GridError(f"{name} header", hx, "cellsize (or dx and dy) must be > 0")
    if "xllcenter" in head and "yllcenter" in head:
        x0, y0 = head["xllcenter"], head["yllcenter"]
    elif "xllcorner" in head and "yllcorner" in head:
        x0, y0 = head["xllcorner"] + 0.5 * hx, head["yllcorner"] + 0.5 * hy
    else:
        raise GridError(f"{name} header", sorted(head), "needs xllcorner and yllcorner, or "
                        "xllcenter and yllcenter")
    rows = lines[k:]
    if len(rows) != ny:
        raise GridError(f"{name}", len(rows), f"{ny} rows of elevations expected (nrows), "
                        f"got {len(rows)}")
    z = np.empty((ny, nx))
    for r, line in enumerate(rows):
        try:
            vals = [float(c) for c in line.split()]
        except ValueError:
            raise GridError(f"{name} row {r}", line[:40], "not numbers") from None
        if len(vals) != nx:
            raise GridError(f"{name} row {r}", len(vals), f"{nx} values expected (ncols)")
        z[ny - 1 - r] = vals  # the first row is the northern one
    if "nodata_value" in head:
        z[z == head["nodata_value"]] = np.nan
    return ElevationGrid(name, x0 + hx * np.arange(nx), y0 + hy * np.arange(ny), z)


def _read_xyz(name: str, text: str) -> ElevationGrid:
    rows = []
    for n, line in enumerate(text.splitlines(), start=1):
        body = line.split("#", 1)[0].strip()
        if not body:
            continue
        cells = body.replace(";", ",").replace(",", " ").split()
        try:
            xyz = [float(c) for c in cells]
        except ValueError:
            if not rows:
                continue  # a header
            raise GridError(f"{name} line {n}", line, "not three numbers x, y, z") from None
        if len(xyz) != 3:
            raise GridError(f"{name} line {n}", line, "not three numbers x, y, z")
        rows.append(xyz)
    pts = np.array(rows, float).reshape(-1, 3)
    axes, index = [], []
    for axis in (0, 1):
        c = pts[:, axis]
        # coordinates as written (0.3 and 0.30000000000000004 are one): to 1e-9 of the span
        tol = 1e-9 * max(np.ptp(c), 1.0)
        u = np.unique(c)
        keep = np.concatenate([[True], np.diff(u) > tol])
        u = u[keep]
        axes.append(u)
        index.append(np.clip(np.searchsorted(u, c - tol), 0, len(u) - 1))
    (xs, ys), (ix, iy) = axes, index
    if len(xs) < 2 or len(ys) < 2:
        raise GridError(name, len(pts), "a grid needs at least 2 distinct x and 2 distinct y")
    for axis, c in (("x", xs), ("y", ys)):
        step = np.diff(c)
        if np.ptp(step) > 1e-6 * step.mean():
            raise GridError(name, f"{axis} steps {step.min():g} to {step.max():g}",
                            f"the points' {axis} must be evenly spaced (a regular grid)")
        if axis == "x":
            xs = c[0] + step.mean() * np.arange(len(c))
        else:
            ys = c[0] + step.mean() * np.arange(len(c))
    z = np.full((len(ys), len(xs)), np.nan)
    seen = np.zeros(z.shape, np.int64)
    np.add.at(seen, (iy, ix), 1)
    if np.any(seen != 1):
        j, i = np.argwhere(seen != 1)[0]
        raise GridError(name, f"x = {xs[i]:g}, y = {ys[j]:g}",
                        f"{seen[j, i]} points there: a regular grid has every (x, y) once")
    z[iy, ix] = pts[:, 2]
    return ElevationGrid(name, xs, ys, z)


def grid_triangles(grid: ElevationGrid) -> tuple[np.ndarray, np.ndarray]:
    """(points (k, 3), triangles (m, 3)): the grid's nodes and two triangles in every cell
    whose four corners have data (a surface for `geometry/surfaces.py`)."""
    ny, nx = grid.z.shape
    gx, gy = np.meshgrid(grid.x, grid.y)
    points = np.column_stack([gx.ravel(), gy.ravel(), grid.z.ravel()])
    j, i = np.mgrid[0:ny - 1, 0:nx - 1]
    a = (j * nx + i).ravel()
    b, c, d = a + 1, a + nx + 1, a + nx
    ok = np.isfinite(points[a, 2]) & np.isfinite(points[b, 2]) & np.isfinite(
        points[c, 2]) & np.isfinite(points[d, 2])
    tri = np.concatenate([np.stack([a, b, c], axis=1)[ok], np.stack([a, c, d], axis=1)[ok]])
    return points, tri


def check_cover(grid: ElevationGrid, px: np.ndarray, py: np.ndarray, what: str) -> np.ndarray:
    """The elevations at the points (px, py), every one of which the grid must cover with
    data; GridError naming the first point outside it or in a cell without data, and the
    grid's row and column there. `what` says what the points are (for the rule)."""
    z = grid.at(px, py)
    bad = np.flatnonzero(~np.isfinite(z))
    if len(bad):
        k = int(bad[0])
        x, y = float(px[k]), float(py[k])
        inside = grid.x[0] <= x <= grid.x[-1] and grid.y[0] <= y <= grid.y[-1]
        if inside:
            node = grid.where(*grid.missing_corner(x, y))
            raise GridError(f"{grid.path} at {node}", f"x = {x:g}, y = {y:g}",
                            f"no data (NODATA or NaN) where {what}")
        raise GridError(grid.path, f"x = {x:g}, y = {y:g}",
                        f"outside the grid (x {grid.x[0]:g} to {grid.x[-1]:g}, y "
                        f"{grid.y[0]:g} to {grid.y[-1]:g}): it must cover {what}")
    return z


def check_layer_grids(layer, key: str, xs: np.ndarray, ys: np.ndarray
                      ) -> tuple[ElevationGrid, ElevationGrid]:
    """A 3D `[[particles.layers]]` table at `key`: its top and bottom elevation grids,
    each with data at every lattice column (xs, ys: the domain lattice's x and y), the
    bottom nowhere above the top there. Raises SceneRule (key, value, rule)."""
    from psph.errors import SceneRule

    gx, gy = (a.ravel() for a in np.meshgrid(xs, ys))
    grids, z = {}, {}
    for side in ("top", "bottom"):
        value = getattr(layer, side)
        if isinstance(value, str) and not Path(value).is_file():
            raise SceneRule(f"{key}.{side}", value, "no such file")
        if not is_grid_file(value):
            raise SceneRule(f"{key}.{side}", value if isinstance(value, str) else "inline",
                            "in 3D a layer's top and bottom are elevation grids (an ESRI "
                            ".asc file or an x, y, z CSV)")
        try:
            grids[side] = read_grid(value)
            z[side] = check_cover(grids[side], gx, gy, "the domain's lattice columns "
                                  "hold soil")
        except GridError as e:
            raise SceneRule(f"{key}.{side} = {e.where}", e.value, e.rule) from None
    gap = z["top"] - z["bottom"]
    scale = max(np.ptp(z["top"]), np.ptp(z["bottom"]), 1.0)
    if np.any(gap < -1e-9 * scale):
        k = int(np.argmin(gap))
        node = grids["bottom"].where(gx[k], gy[k])
        raise SceneRule(f"{key}.bottom = {grids['bottom'].path} near {node}",
                        f"x = {gx[k]:g}, y = {gy[k]:g}",
                        f"above the top (by {-gap[k]:g} m): the surfaces cross")
    return grids["top"], grids["bottom"]


def check_table_over_bedrock(table, bottoms: list[ElevationGrid], px: np.ndarray,
                             py: np.ndarray) -> None:
    """A saturated scene's water table (an elevation grid, or a level) nowhere below the
    bedrock, the lowest of the layers' `bottoms`, at the lattice columns (px, py): there
    the soil above would hold no water table. GridError names the table's node (a level:
    the column) and the bedrock's grid."""
    low = np.stack([b.at(px, py) for b in bottoms])
    which = np.argmin(low, axis=0)
    rock = low[which, np.arange(len(px))]
    z = table.at(px, py) if isinstance(table, ElevationGrid) else np.full(len(px), table)
    gap = z - rock
    scale = max(float(np.ptp(rock)), 1.0)
    if np.all(gap >= -1e-9 * scale):
        return
    k = int(np.argmin(gap))
    x, y = float(px[k]), float(py[k])
    where = f"{table.path} at {table.where(x, y)}" if isinstance(table, ElevationGrid) \
        else "level"
    raise GridError(where, f"x = {x:g}, y = {y:g}",
                    f"{-gap[k]:g} m below the bedrock ({bottoms[which[k]].path} at "
                    f"{bottoms[which[k]].where(x, y)}, z = {rock[k]:g} m): a saturated "
                    "layer needs its water table above the bedrock")

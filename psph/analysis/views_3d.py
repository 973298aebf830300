"""Pictures of a 3D run, drawn with matplotlib: a vertical section through the
mass, a plan view of the deposit (its footprint coloured by thickness), and a perspective
view, each of the last snapshot coloured by a field."""

from pathlib import Path

import numpy as np

from psph.geometry.columns import column_tops

MAX_POINTS = 60_000  # the perspective view draws at most this many particles


def field_values(snap: dict, field: str) -> np.ndarray:
    """A scalar per particle: the field itself, the norm of a vector, or the vertical
    stress (zz) of the stress."""
    val = snap[field]
    if val.ndim == 1:
        return val
    return val[:, 2] if field == "stress" else np.linalg.norm(val, axis=1)


def section_row(x: np.ndarray, dx: float, front_plane: bool) -> np.ndarray:
    """Mask of the particles of the vertical x-z section: the lattice row nearest the
    middle of the mass in y, or the row next to y = min (a symmetry plane at the front
    wall: the centre line of a quarter or half model)."""
    y = x[:, 1]
    y0 = y.min() if front_plane else 0.5 * (y.min() + y.max())
    return np.abs(y - y0) <= 0.5 * dx + 0.25 * dx if front_plane else \
        np.abs(y - y[np.argmin(np.abs(y - y0))]) < 0.5 * dx


def deposit_thickness(x: np.ndarray, dx: float, base: float) -> tuple[np.ndarray, tuple]:
    """Thickness of the mass in each dx x dx column of the plan (top of the highest
    particle above `base`; NaN where the column is empty) and the grid's extent."""
    lo = x[:, :2].min(axis=0) - 0.5 * dx
    shape = tuple(np.floor((x[:, :2] - lo) / dx).astype(np.int64).max(axis=0) + 1)
    top = column_tops(x, lo, dx, shape, 0.5 * dx)
    thick = np.where(np.isfinite(top), top - base, np.nan)
    extent = (lo[0], lo[0] + shape[0] * dx, lo[1], lo[1] + shape[1] * dx)
    return thick, extent


def pictures_3d(out: Path, snap: dict, field: str, dx: float, base: float,
                front_plane: bool) -> list[Path]:
    """section_<field>.png, plan.png and perspective_<field>.png in `out`."""
    import matplotlib.pyplot as plt

    x = snap["x"]
    val = field_values(snap, field)
    title = f"t = {snap['time']:.4g} s"
    paths = []
    # vertical section
    m = section_row(x, dx, front_plane)
    ext = np.ptp(x[m][:, [0, 2]], axis=0) + 1e-12 if m.any() else np.ones(2)
    fig, ax = plt.subplots(figsize=(3 + 6 * ext[0] / ext.max(), 2.5 + 5 * ext[1] / ext.max()))
    sc = ax.scatter(x[m, 0], x[m, 2], c=val[m], s=6, cmap="viridis")
    fig.colorbar(sc, ax=ax, label=field)
    ax.set(aspect="equal", xlabel="x (m)", ylabel="z (m)",
           title=f"{field}, section y = {x[m, 1].mean() if m.any() else 0:.3g} m, {title}")
    paths.append(_save(fig, out / f"section_{field}.png"))
    # plan: footprint and thickness
    thick, extent = deposit_thickness(x, dx, base)
    fig, ax = plt.subplots(figsize=(6, 5))
    im = ax.imshow(thick.T, origin="lower", extent=extent, cmap="terrain")
    fig.colorbar(im, ax=ax, label="thickness (m)")
    ax.set(aspect="equal", xlabel="x (m)", ylabel="y (m)",
           title=f"plan: footprint and thickness, {title}")
    paths.append(_save(fig, out / "plan.png"))
    # perspective
    step = max(1, len(x) // MAX_POINTS)
    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    sc = ax.scatter(x[::step, 0], x[::step, 1], x[::step, 2], c=val[::step], s=2,
                    cmap="viridis")
    fig.colorbar(sc, ax=ax, label=field, shrink=0.6)
    span = np.ptp(x, axis=0) + 1e-12
    ax.set_box_aspect(span / span.max())
    ax.set(xlabel="x", ylabel="y", zlabel="z", title=f"{field}, {title}")
    ax.view_init(elev=25, azim=-60)
    paths.append(_save(fig, out / f"perspective_{field}.png"))
    return paths


def _save(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def surface_top(x: np.ndarray, dx: float, lo, shape, base: float) -> np.ndarray:
    """The surface (top particle + dx / 2) of each dx x dx plan column of the grid from
    `lo` with `shape` (nx, ny); `base` where the column is empty."""
    top = column_tops(x, lo, dx, shape, 0.5 * dx)
    return np.where(np.isfinite(top), top, base)


def plan_change_frames(out: Path, snaps: list[dict], dx: float, base: float,
                       mirror: bool = False, name: str = "plan_frames.png") -> Path:
    """Plan views of a slope at up to four snapshot times (after the first, the last
    and two between): the ground surface's change since the first snapshot in each
    dx x dx column, the scarp (lowered, blue) and the deposit (raised, red). `mirror`:
    a half model with its symmetry plane at the lowest y, drawn with its mirror image
    (the whole valley)."""
    import matplotlib.pyplot as plt

    picks = np.unique(np.linspace(1 if len(snaps) > 1 else 0, len(snaps) - 1, 4).astype(int))
    frames = [snaps[i] for i in picks]
    x_all = np.concatenate([snaps[0]["x"]] + [f["x"] for f in frames])
    lo = x_all[:, :2].min(axis=0) - 0.5 * dx
    shape = tuple(int(n) for n in np.floor((x_all[:, :2].max(axis=0) - lo) / dx) + 1)
    top0 = surface_top(snaps[0]["x"], dx, lo, shape, base)
    changes = [surface_top(f["x"], dx, lo, shape, base) - top0 for f in frames]
    lim = max(max(float(np.abs(c).max()) for c in changes), 1e-6)
    y0, y1 = lo[1], lo[1] + shape[1] * dx
    if mirror:  # the image across y = y0 below the model
        changes = [np.concatenate([c[:, ::-1], c], axis=1) for c in changes]
        y0 = 2 * lo[1] - y1
    extent = (lo[0], lo[0] + shape[0] * dx, y0, y1)
    aspect = (y1 - y0) / (shape[0] * dx)
    fig, axes = plt.subplots(len(frames), 1, squeeze=False,
                             figsize=(12, 0.8 + len(frames) * (12 * aspect + 0.6)))
    for ax, f, c in zip(axes[:, 0], frames, changes, strict=True):
        im = ax.imshow(c.T, origin="lower", extent=extent, cmap="RdBu_r", vmin=-lim,
                       vmax=lim, aspect="equal")
        whole = ", mirrored across the symmetry plane" if mirror else ""
        ax.set_title(f"surface change since t = {snaps[0]['time']:.3g} s, at t = "
                     f"{f['time']:.3g} s{whole}", fontsize=9)
        ax.set(xlabel="x (m)", ylabel="y (m)")
        fig.colorbar(im, ax=ax, label="dz (m)", shrink=0.9)
    return _save(fig, out / name)

"""Metrics of a 3D slope failure (scene `slope_3d`): the 2D metrics of Section
4.5 read on the centre line's section, and what only a plan shows.

- On the centre line (a 2 dx wide strip at the front symmetry plane of a half model, or
  at the middle of the width): the run-out, the back scarp, the successive slides and
  the excess pore pressure, the section seen as the 2D scene
  (`collapse.plane_strain_view`, `collapse.collapse_metrics`), so the numbers are those
  of `retrogressive_k0_0.5`.
- In plan: the retrogression (the centre line's back scarp behind its initial place);
  the scarp's width (across the valley: the width of the rows in y that hold a 2 dx x
  2 dx column of the initially level top whose surface has dropped below 95 % of the
  slope's height, the last row cut at the domain's side); the
  debris (particles moved more than `DEBRIS_DX` dx): its footprint (the plan area of the
  dx x dx columns holding debris) and its volume (the sum of the debris particles' V).
  With a symmetry plane at the front (a half model) the width, area and volume are the
  valley's: twice the model's.

Collective: each rank reads its share of each snapshot's rows (no global arrays but the
plan's column grids).
"""

import h5py
import numpy as np
from mpi4py import MPI

from psph.geometry.columns import column_grid, column_index, column_tops
from psph.verify.collapse import collapse_metrics, plane_strain_view, series_block, slides_from
from psph.verify.distributed import exact_dot, read_share
from psph.verify.pressure import DEBRIS_DX, pressure_quality_from, snapshot_quality

SCARP_DROP = 0.95  # a column of the level top is in the scarp once below this of h0


def centre_strip(scene) -> tuple[float, float, bool]:
    """(y_lo, y_hi, mirrored): the centre line's strip, 2 dx wide, at the front wall when
    it is a symmetry plane (a half model: mirrored), else about the middle of the width."""
    dx = scene.particles.dx
    y0, y1 = scene.domain.min[1], scene.domain.max[1]
    front = scene.boundaries.front
    if front.motion == "slip" and front.symmetry:
        return y0, y0 + 2.0 * dx, True
    mid = 0.5 * (y0 + y1)
    return mid - dx, mid + dx, False


def centre_section(snap: dict, scene) -> dict:
    """A whole snapshot's centre line (`centre_strip`) as a 2D snapshot in the x-z plane
    (`collapse.plane_strain_view`): every per-particle field of the strip's rows."""
    ylo, yhi, _ = centre_strip(scene)
    y = snap["x"][:, 1]
    strip = (y >= ylo) & (y < yhi)
    n = len(y)
    rows = {k: v[strip] if isinstance(v, np.ndarray) and v.shape[:1] == (n,) else v
            for k, v in snap.items()}
    return plane_strain_view(rows)


def plan_metrics(x: np.ndarray, u: np.ndarray, vol: np.ndarray, scene, h0: float,
                 comm) -> dict:
    """The plan's numbers of one snapshot (this rank's rows x, u (n, 3) and V; collective):
    the scarp's width across the valley, the debris' footprint area and volume (the
    valley's with a front symmetry plane: `centre_strip`)."""
    dx = scene.particles.dx
    lo = np.array(scene.domain.min[:2], float)
    hi = np.array(scene.domain.max[:2], float)
    mirror = 2.0 if centre_strip(scene)[2] else 1.0
    # the scarp: columns 2 dx wide of the level top (initially above 0.95 h0), now below
    top, top0 = (_column_top(p, lo, hi, 2.0 * dx, dx, comm) for p in (x, x - u))
    scarp = (top0 >= SCARP_DROP * h0) & (top < SCARP_DROP * h0)
    rows = np.flatnonzero(scarp.any(axis=0))  # rows of columns across the valley (y)
    edges = np.minimum(lo[1] + 2.0 * dx * np.stack([rows, rows + 1]), hi[1])
    width = mirror * float(np.sum(edges[1] - edges[0]))
    # the debris: moved more than DEBRIS_DX dx
    debris = np.linalg.norm(u, axis=1) > DEBRIS_DX * dx
    shape = column_grid(lo, hi, dx)
    cover = np.zeros(shape, np.int8)
    ix, iy = column_index(x[debris], lo, dx, shape)
    cover[ix, iy] = 1
    comm.Allreduce(MPI.IN_PLACE, cover, op=MPI.MAX)
    area = mirror * dx * dx * float(cover.sum())
    volume = mirror * exact_dot(vol, debris.astype(float), comm)
    return {"scarp_width_m": width, "footprint_area_m2": area, "debris_volume_m3": volume}


def _column_top(x: np.ndarray, lo, hi, c: float, dx: float, comm) -> np.ndarray:
    """The surface (top particle + dx / 2) of each c x c plan column over all ranks;
    -inf where empty."""
    top = column_tops(x, lo, c, column_grid(lo, hi, c), 0.5 * dx)
    comm.Allreduce(MPI.IN_PLACE, top, op=MPI.MAX)
    return top


def slope_verification(path, scene, comm) -> dict:
    """The `metrics` block of a 3D slope run from its snapshots `path` (particles.h5):
    `collapse` (the centre line's section, the keys of the 2D scene's), `pressure_quality`
    (of that section) and `slope_3d` (the plan's series, and its values at each slide).
    Collective."""
    dx = scene.particles.dx
    ylo, yhi, mirrored = centre_strip(scene)
    names = ("id", "x", "u", "p", "stress", "vol")
    snaps, rows, plans = [], [], []
    with h5py.File(path, "r") as f:
        for name in sorted(f["snapshots"]):
            g = f["snapshots"][name]
            share = read_share(g, names, comm)
            time = float(g.attrs["time"])
            x = share["x"]
            section = centre_section(share, scene)
            section["time"] = time
            m = collapse_metrics(section["x"], section["x"] - section["u"], dx, comm)
            m["time_s"] = time
            m["plastic_work_J_per_m"] = None
            snaps.append(m)
            rows.append(snapshot_quality(section, scene, comm, checkerboard=False))
            plans.append(plan_metrics(x, share["u"], share["vol"], scene,
                                      snaps[0]["initial_height_m"], comm))
    collapse = series_block(snaps, rows)
    times = np.array(collapse["series"]["time_s"])
    scarps = np.array(collapse["series"]["back_scarp_m"])
    collapse.update(slides_from(times, scarps, snaps[0]["initial_height_m"], dx))
    retro = (scarps[0] - np.minimum.accumulate(scarps)).tolist()
    series = {"time_s": times.tolist(), "retrogression_m": retro}
    for k in plans[0]:
        series[k] = [p[k] for p in plans]
    at_slides = []
    for t in collapse["slide_times_s"]:
        k = int(np.argmin(np.abs(times - t)))
        at_slides.append({"time_s": float(times[k]), "retrogression_m": retro[k],
                          "scarp_width_m": series["scarp_width_m"][k]})
    plan = {"mirrored": mirrored, "section_y_m": [ylo, yhi],
            "retrogression_m": retro[-1], **plans[-1], "at_slides": at_slides,
            "series": series}
    return {"collapse": collapse, "time_s": float(times[-1]),
            "pressure_quality": pressure_quality_from(rows, scene), "slope_3d": plan}

"""Pressure quality of a saturated collapse or slope run (Sections 4.4-4.5), from its
snapshots, on rank 0 in post-processing (numpy only).

- excess pore pressure: p minus the hydrostatic pressure of the water table at each
  particle's current position (what the paper's Figs. 14-17, 20 and 24 show);
- its percentiles and extremes at each snapshot;
- a checkerboard index of p and of the mean effective stress p' = -(s'xx + s'yy + s'zz)/3:
  the particle-scale, odd-even noise of the debris (cf. the pressure
  noise of the unstabilised run, Fig. 22, and the Shepard filter Eq. (46));
- the excess over the current phreatic line (`phreatic_excess`: drainage through a free
  face is not read as negative excess) and the suction max(-p, 0): their 99th
  percentiles.

`python -m psph.analysis.pressure OUT [OUT ...] [--write]` prints one line per run and
with `--write` stores the block as `metrics.pressure_quality` in each OUT/summary.json.
"""

import math

import numpy as np
from mpi4py import MPI

from psph.kernels.spline import ALPHA_2D
from psph.physics.initial import table_elevation
from psph.verify.distributed import extreme, percentiles, with_halo

DEBRIS_DX = 5.0  # a particle that moved more than this many dx is "debris"
PERCENTILES = (1, 5, 50, 95, 99)
SURFACE_BIN = 0.25  # bin width of the ground-surface search, in dx
SURFACE_REACH = 3  # bins either side of a particle's own bin (a window about 2 dx wide)
PHREATIC_ROWS = 2.0  # p above gamma_l PHREATIC_ROWS dx: below the phreatic line


def ground_surface(x: np.ndarray, dx: float, comm=None) -> np.ndarray:
    """Elevation (m) of the highest particle centre above each particle.

    The search window is the particle's own bin of width dx/4 and 3 bins on either side,
    i.e. a column about 2 dx wide centred on the particle (1.5-2 dx; the bins are anchored
    half a spacing left of the leftmost particle, so on the initial lattice a particle's
    window holds its own lattice column only, as in psph/physics/initial.py). A particle
    splashed above the mass lifts the surface of the particles below it.
    `x` may be this rank's share of the particles (collective over `comm`: the bins'
    maxima are reduced over the ranks).
    """
    x = np.asarray(x, dtype=float).reshape(-1, 2)
    return column_max(x, x[:, 1], dx, comm)


def column_max(x: np.ndarray, values: np.ndarray, dx: float, comm=None) -> np.ndarray:
    """The largest of `values` (one per particle; -inf: none) in each particle's column
    of `ground_surface` (about 2 dx wide; collective over `comm`)."""
    comm = MPI.COMM_SELF if comm is None else comm
    x = np.asarray(x, dtype=float).reshape(-1, 2)
    b = SURFACE_BIN * dx
    x_min = -comm.allreduce(-float(x[:, 0].min()) if len(x) else -np.inf, op=MPI.MAX)
    k = np.floor((x[:, 0] - (x_min - 0.5 * dx)) / b).astype(np.int64)
    k_max = comm.allreduce(int(k.max()) if len(k) else -1, op=MPI.MAX)
    if k_max < 0:
        return np.zeros(0)
    m = SURFACE_REACH
    top = np.full(k_max + 1 + 2 * m, -np.inf)
    np.maximum.at(top, k + m, np.asarray(values, dtype=float))
    if comm.Get_size() > 1:
        comm.Allreduce(MPI.IN_PLACE, top, op=MPI.MAX)
    windowed = top.copy()
    for s in range(1, m + 1):  # sliding maximum over 2m + 1 bins
        windowed[m:-m] = np.maximum(windowed[m:-m], np.maximum(top[m - s:len(top) - m - s],
                                                               top[m + s:len(top) - m + s]))
    return windowed[k + m]


def hydrostatic_pressure(x: np.ndarray, scene, surface_y: np.ndarray | float | None = None,
                         comm=None) -> np.ndarray:
    """Hydrostatic pore pressure (Pa) of the water table at each particle's current
    position x (N, 2): gamma_l max(0, y_w - y), gamma_l = rho_l |g| (the initial state,
    `initial.water_table`, Sections 4.4-4.5).

    y_w, from `scene.initial.water_table`:

    - "surface": the ground surface above the particle, taken as the centre of the highest
      particle in a column about 2 dx wide around it (`ground_surface`). The soil of this
      model is fully saturated (no unsaturated zone, no free water), so its water table is
      its current surface. The centre, not the top (y + dx/2), is the convention of the
      initial state (psph/physics/initial.py: p = 0 at the top particle's centre), so a
      column at rest has zero excess pressure.
    - a number (an elevation) or a phreatic profile (its elevation at the particle's
      current x, `table_elevation`): that level, but never above the current ground surface of
      the particle's column: water does not stand above the soil in this model (ponding
      keeps p <= 0 on the free surface), so where the mass has spread below the level
      (the debris of the Section 4.4 collapse) the table follows the surface. Before the
      mass moves this is the level itself.
    - None: zero.

    `surface_y`: the ground-surface elevation per particle (N,) or one value, if known;
    by default `ground_surface(x, dx, comm)` (collective; `x` this rank's share).
    """
    x = np.asarray(x, dtype=float).reshape(-1, 2)
    if scene.initial.water_table is None:
        return np.zeros(len(x))
    gamma = scene.material.rho_l * float(np.linalg.norm(scene.gravity))
    return gamma * np.maximum(table_level(x, scene, surface_y, comm) - x[:, 1], 0.0)


def table_level(x: np.ndarray, scene, surface_y: np.ndarray | float | None = None,
                comm=None) -> np.ndarray:
    """The water table's elevation y_w (m) above each particle, as `hydrostatic_pressure`
    defines it (-inf without `initial.water_table`; collective over `comm` like it)."""
    x = np.asarray(x, dtype=float).reshape(-1, 2)
    table = scene.initial.water_table
    if table is None:
        return np.full(len(x), -np.inf)
    surface = ground_surface(x, scene.particles.dx, comm) if surface_y is None \
        else np.broadcast_to(np.asarray(surface_y, dtype=float), (len(x),))
    if table == "surface":
        return np.array(surface, dtype=float)
    return np.minimum(table_elevation(table, x), surface)


def excess_pressure(snap: dict, scene, comm=None) -> np.ndarray:
    """Excess pore pressure p - `hydrostatic_pressure` (Pa) of one snapshot (a dict of
    `psph.io.snapshots.read_snapshots`: x, u, p, stress, id, ...; or this rank's share of
    its rows, collective over `comm`)."""
    return snap["p"] - hydrostatic_pressure(snap["x"], scene, comm=comm)


def wet_threshold(scene) -> float:
    """The pore pressure (Pa) of PHREATIC_ROWS rows of water, gamma_l 2 dx: above it a
    particle is below the phreatic line; |p| below it is drained, -p above it suction
    (the particle-scale noise of p is smaller)."""
    return PHREATIC_ROWS * scene.material.rho_l * float(np.linalg.norm(scene.gravity)) \
        * scene.particles.dx


def phreatic_level(x: np.ndarray, p: np.ndarray, scene, comm=None) -> np.ndarray:
    """Elevation (m) of the current phreatic line above each particle: the highest
    piezometric head y + p / gamma_l in its column (`column_max`) among the particles
    whose p exceeds the hydrostatic pressure of PHREATIC_ROWS rows (gamma_l 2 dx, above
    the particle-scale noise of p), never above `hydrostatic_pressure`'s table; -inf in a
    column where no particle holds that much (drained to its floor). Where the soil has
    drained through a free face, the line falls below the ground surface (the paper's
    Fig. 16 text: "a well-defined curvature phreatic line, above which the pore-water
    pressure is zero"); elsewhere it is the table."""
    x = np.asarray(x, dtype=float).reshape(-1, 2)
    gamma = scene.material.rho_l * float(np.linalg.norm(scene.gravity))
    dx = scene.particles.dx
    wet = p > wet_threshold(scene)
    head = np.where(wet, x[:, 1] + p / gamma, -np.inf)
    return np.minimum(column_max(x, head, dx, comm), table_level(x, scene, comm=comm))


def phreatic_excess(snap: dict, scene, comm=None) -> np.ndarray:
    """Excess pore pressure (Pa) over the hydrostatic pressure of the current phreatic
    line (`phreatic_level`): p where the column has drained below the particle (the
    paper's reading: above the phreatic line "negative pore-water pressure (i.e., equal to
    excess pore-water pressure in this case)"), `excess_pressure` where the line is the
    table. Collective over `comm` like `excess_pressure`."""
    x = np.asarray(snap["x"], dtype=float).reshape(-1, 2)
    gamma = scene.material.rho_l * float(np.linalg.norm(scene.gravity))
    level = phreatic_level(x, snap["p"], scene, comm)
    return snap["p"] - gamma * np.maximum(level - x[:, 1], 0.0)


def suction_integral(snap: dict, comm=None) -> float:
    """The suction of a snapshot summed over the soil: sum_i V_i max(-p_i, 0) (N per metre
    of a 2D section), with V_i the particle's current area (`vol`). Where a single
    particle's most negative p tells how deep the suction goes, this tells how much of
    the soil holds it and how strongly (the "pore fluid pressure field" of the paper's
    Fig. 16). Collective over `comm` like `excess_pressure`."""
    comm = MPI.COMM_SELF if comm is None else comm
    return comm.allreduce(float(np.sum(snap["vol"] * np.maximum(-snap["p"], 0.0))))


def mean_effective_stress(stress: np.ndarray) -> np.ndarray:
    """p' = -(s'xx + s'yy + s'zz) / 3 (Pa, compression positive) from the effective stress
    columns xx, yy, zz, xy, ... (tension positive, Eq. (2))."""
    return -(stress[:, 0] + stress[:, 1] + stress[:, 2]) / 3.0


def cubic_spline(r: np.ndarray, h: float) -> np.ndarray:
    """Kernel W(r, h) of Eq. (21) in 2D (inner branch q^3/2, as psph/kernels/spline.py)."""
    q = np.asarray(r, dtype=float) / h
    t = np.clip(2.0 - q, 0.0, None)
    w = np.where(q < 1.0, 2.0 / 3.0 - q * q + 0.5 * q ** 3, t ** 3 / 6.0)
    return ALPHA_2D / (h * h) * w


def neighbour_pairs(x: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All ordered pairs (i, j), i != j, closer than `radius`, with their distance: a
    cell list of square cells of side `radius` (vectorised; no pair loop)."""
    x = np.asarray(x, dtype=float)
    ok = np.all(np.isfinite(x), axis=1)
    idx = np.flatnonzero(ok)
    if len(idx) < 2:
        empty = np.zeros(0, np.int64)
        return empty, empty, np.zeros(0)
    c = np.floor((x[idx] - x[idx].min(axis=0)) / radius).astype(np.int64)
    width = int(c[:, 0].max()) + 3  # columns shifted by 1: the -1 and +1 offsets never wrap
    cid = c[:, 1] * width + c[:, 0] + 1
    order = np.argsort(cid, kind="stable")
    sorted_cid = cid[order]
    ii, jj = [], []
    for oy in (-1, 0, 1):
        for ox in (-1, 0, 1):
            nb = (c[:, 1] + oy) * width + c[:, 0] + 1 + ox
            start = np.searchsorted(sorted_cid, nb, side="left")
            count = np.searchsorted(sorted_cid, nb, side="right") - start
            total = int(count.sum())
            if total == 0:
                continue
            first = np.cumsum(count) - count
            a = np.repeat(np.arange(len(idx)), count)
            b = order[np.repeat(start, count) + np.arange(total) - np.repeat(first, count)]
            ii.append(a)
            jj.append(b)
    i = np.concatenate(ii)
    j = np.concatenate(jj)
    r = np.linalg.norm(x[idx[i]] - x[idx[j]], axis=1)
    keep = (i != j) & (r < radius)
    return idx[i[keep]], idx[j[keep]], r[keep]


def checkerboard_index(x: np.ndarray, f: np.ndarray, h: float, mask: np.ndarray | None = None,
                       pairs: tuple | None = None, comm=None, n_owned: int | None = None
                       ) -> float:
    """Particle-scale (odd-even) noise of a field f at positions x (N, 2).

    index = rms_i (f_i - fbar_i) / rms_i (f_i - mean f), over the particles i of `mask`
    (all by default), where fbar_i = sum_j W_ij f_j / sum_j W_ij is the Shepard average
    (Eq. (46) with equal volumes) over the OTHER particles j != i within 2h, W the cubic
    spline of Eq. (21) (h = scene.h = 1.2 dx by default). Every particle is a neighbour,
    masked or not; a particle without neighbours is left out.

    A smooth (linear) field gives ~0 away from the edges; an odd-even checkerboard on a
    square lattice gives 1.45 (fbar_i = -0.45 f_i at h = 1.2 dx). By convention 0 when
    f is constant over the mask (rms = 0). `pairs`: `neighbour_pairs(x, 2h)`, if known.
    Returns NaN when the mask selects no particle with neighbours.

    Over ranks (`comm`): rows 0..n_owned-1 are this rank's particles i, the rest copies of
    other ranks' particles within 2h (`with_halo`), neighbours only; the rms and the mean
    are sums reduced over the ranks.
    """
    comm = MPI.COMM_SELF if comm is None else comm
    f = np.asarray(f, dtype=float)
    n = len(f)
    n_owned = n if n_owned is None else n_owned
    sel = np.ones(n, bool) if mask is None else np.asarray(mask, bool)
    i, j, r = neighbour_pairs(x, 2.0 * h) if pairs is None else pairs
    keep = i < n_owned
    i, j, r = i[keep], j[keep], r[keep]
    w = cubic_spline(r, h)
    den = np.bincount(i, weights=w, minlength=n)[:n_owned]
    num = np.bincount(i, weights=w * f[j], minlength=n)[:n_owned]
    f = f[:n_owned]
    use = sel[:n_owned] & (den > 0) & np.isfinite(f)
    count = comm.allreduce(int(use.sum()))
    if count == 0:
        return math.nan
    fbar = num[use] / den[use]
    mean = comm.allreduce(float(f[use].sum())) / count
    spread = math.sqrt(comm.allreduce(float(np.sum((f[use] - mean) ** 2))) / count)
    f_max = comm.allreduce(float(np.max(np.abs(f[use]))) if use.any() else 0.0, op=MPI.MAX)
    if spread == 0.0 or spread < 1e-12 * f_max:
        return 0.0
    return math.sqrt(comm.allreduce(float(np.sum((f[use] - fbar) ** 2))) / count) / spread


def _num(v: float) -> float | None:
    """JSON-safe float: NaN becomes None."""
    return None if v is None or not math.isfinite(v) else float(v)


def snapshot_quality(snap: dict, scene, comm=None, checkerboard: bool = True) -> dict:
    """Pressure quality of one snapshot: percentiles and extremes of the excess pressure
    (with the particle's id and position), the 99th percentiles of |excess over the
    phreatic line| and of the suction, and the checkerboard index of p and p' over all
    particles and over the debris (moved more than 5 dx from x - u, the initial place).
    `snap` may hold this rank's share of the rows (collective over `comm`; the same
    numbers on any number of ranks but for the rounding of the checkerboard's sums).
    checkerboard = False leaves the checkerboard indices out (None): a 3D slab seen in its
    x-z plane (`collapse.plane_strain_view`) has its particles' rows on top of each other."""
    comm = MPI.COMM_SELF if comm is None else comm
    x = snap["x"]
    ids = snap["id"] if "id" in snap else np.arange(len(x))
    ex = excess_pressure(snap, scene, comm)
    pct = percentiles(ex, PERCENTILES, comm)
    ex_min, id_min, x_min = extreme(ex, ids, x, comm, largest=False)
    ex_max, id_max, x_max = extreme(ex, ids, x, comm, largest=True)
    debris = np.linalg.norm(snap["u"], axis=1) > DEBRIS_DX * scene.particles.dx
    n_debris = comm.allreduce(int(debris.sum()))
    out = {"time_s": float(snap["time"])}
    for q, v in zip(PERCENTILES, pct, strict=True):
        out[f"excess_p{q}_Pa"] = float(v)
    out["abs_excess_p99_Pa"] = percentiles(np.abs(ex), [99], comm)[0]
    # the same over the current phreatic line (drawdown through a drained face not read
    # as negative excess), and the negative pore pressure itself
    out["abs_phreatic_excess_p99_Pa"] = percentiles(
        np.abs(phreatic_excess(snap, scene, comm)), [99], comm)[0]
    out["suction_p99_Pa"] = percentiles(np.maximum(-snap["p"], 0.0), [99], comm)[0]
    out.update({"excess_min_Pa": ex_min, "excess_min_id": id_min, "excess_min_x_m": x_min,
                "excess_max_Pa": ex_max, "excess_max_id": id_max, "excess_max_x_m": x_max,
                "debris_particles": n_debris})
    if not checkerboard:
        for name in ("p", "p_eff"):
            out[f"checkerboard_{name}_all"] = out[f"checkerboard_{name}_debris"] = None
        return out
    xs, fs, n_owned = with_halo(x, {"p": snap["p"],
                                    "p_eff": mean_effective_stress(snap["stress"]),
                                    "debris": debris.astype(float)}, 2.0 * scene.h, comm)
    pairs = neighbour_pairs(xs, 2.0 * scene.h)
    debris = fs["debris"] > 0.5
    for name in ("p", "p_eff"):
        out[f"checkerboard_{name}_all"] = _num(checkerboard_index(
            xs, fs[name], scene.h, None, pairs, comm, n_owned))
        out[f"checkerboard_{name}_debris"] = _num(checkerboard_index(
            xs, fs[name], scene.h, debris, pairs, comm, n_owned)) if n_debris else None
    return out


def pressure_quality(snaps: list[dict], scene) -> dict:
    """The `metrics.pressure_quality` block of summary.json for a run's snapshots
    (`read_snapshots`): `series` holds each quantity of `snapshot_quality` as a list over
    the snapshot times, `over_run` the extremes over all snapshots and the last snapshot's
    checkerboard indices. JSON-serialisable (floats, ints, lists; None for undefined)."""
    return pressure_quality_from([snapshot_quality(s, scene) for s in snaps], scene)


def pressure_quality_from(rows: list[dict], scene) -> dict:
    """`pressure_quality`'s block from the rows of `snapshot_quality`, one a snapshot."""
    series = {k: [r[k] for r in rows] for k in rows[0]} if rows else {}
    over = {}
    if rows:
        kmin = int(np.argmin(series["excess_min_Pa"]))
        kmax = int(np.argmax(series["excess_max_Pa"]))
        over = {"excess_min_Pa": series["excess_min_Pa"][kmin],
                "excess_min_id": series["excess_min_id"][kmin],
                "excess_min_time_s": series["time_s"][kmin],
                "excess_min_x_m": series["excess_min_x_m"][kmin],
                "excess_max_Pa": series["excess_max_Pa"][kmax],
                "excess_max_id": series["excess_max_id"][kmax],
                "excess_max_time_s": series["time_s"][kmax],
                "excess_max_x_m": series["excess_max_x_m"][kmax],
                "excess_p1_min_Pa": min(series["excess_p1_Pa"]),
                "excess_p99_max_Pa": max(series["excess_p99_Pa"]),
                "abs_excess_p99_max_Pa": max(series["abs_excess_p99_Pa"]),
                "abs_phreatic_excess_p99_max_Pa": max(series["abs_phreatic_excess_p99_Pa"]),
                "suction_p99_max_Pa": max(series["suction_p99_Pa"])}
        for k in ("checkerboard_p_all", "checkerboard_p_debris", "checkerboard_p_eff_all",
                  "checkerboard_p_eff_debris"):
            vals = [v for v in series[k] if v is not None]
            over[f"{k}_max"] = max(vals) if vals else None
            over[f"{k}_last"] = series[k][-1]
    table = scene.initial.water_table
    return {"water_table": table if table is None or isinstance(table, (str, list))
            else float(table),
            "debris_moved_more_than_m": DEBRIS_DX * scene.particles.dx,
            "h_m": scene.h, "over_run": over, "series": series}

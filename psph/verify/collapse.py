"""Metrics of a collapse or slope failure from the particle positions (Sections 4.4-4.5):
run-out distance, final height and back-scarp position."""

import h5py
import numpy as np
from mpi4py import MPI

from psph.verify.distributed import exact_dot, percentiles, read_share
from psph.verify.pressure import pressure_quality_from, snapshot_quality


def collapse_metrics(x: np.ndarray, x0: np.ndarray, dx: float, comm=None) -> dict:
    """x, x0: (N, 2) current and initial positions of the particles (this rank's share
    of them; collective over `comm`, default one process).

    - runout_m: how far the toe advanced: the 99.8th percentile of x (a few splashed
      particles do not count) minus the initial largest x;
    - toe_m: that percentile itself;
    - runout_spread_m: the 99.8th minus the 99th percentile of x, the run-out's
      sensitivity to the percentile chosen (its own resolution);
    - final_height_m / initial_height_m: the highest particle within 5 dx of the left
      end of the mass;
    - back_scarp_m: the smallest x where the free surface lies below 95 % of the initial
      height (the crest of the failure), measured in columns of width 2 dx.

    The same numbers on any number of ranks (order statistics, extremes and a maximum
    per column reduced over the ranks; psph/verify/distributed.py).
    """
    comm = MPI.COMM_SELF if comm is None else comm
    toe_99, toe = percentiles(x[:, 0], [99.0, 99.8], comm)
    left = -_max(-x0[:, 0], comm)
    h0 = _max(x0[:, 1], comm) + 0.5 * dx
    near = x[:, 0] < left + 5 * dx
    height = _max(x[near, 1], comm)
    height = height + 0.5 * dx if np.isfinite(height) else 0.0
    col = np.floor((x[:, 0] - left) / (2 * dx)).astype(int)
    col = np.clip(col, 0, None)
    top = np.full(int(_max(col, comm)) + 1, -np.inf)
    np.maximum.at(top, col, x[:, 1] + 0.5 * dx)
    comm.Allreduce(MPI.IN_PLACE, top, op=MPI.MAX)
    low = np.flatnonzero(top < 0.95 * h0)
    scarp = float(left + 2 * dx * low[0]) if len(low) else _max(x[:, 0], comm)
    return {"runout_m": toe - _max(x0[:, 0], comm), "toe_m": toe,
            "runout_spread_m": toe - toe_99,
            "initial_height_m": h0, "final_height_m": height, "back_scarp_m": scarp}


def plane_strain_view(snap: dict) -> dict:
    """A 3D slab's snapshot (x, u as (N, 3), the 6-component stress xx yy zz xy yz zx) in the
    x-z plane of its 2D counterpart: x and u as (N, 2) (x, z) and the stress in the 2D
    order xx, yy (vertical), zz (out of plane), xy, so the 2D metrics read it unchanged.
    A 2D snapshot is returned as it is."""
    if snap["x"].shape[1] != 3:
        return snap
    out = dict(snap)
    out["x"] = snap["x"][:, [0, 2]]
    out["u"] = snap["u"][:, [0, 2]]
    if "stress" in snap:
        out["stress"] = snap["stress"][:, [0, 2, 1, 5]]
    return out


def _max(a: np.ndarray, comm) -> float:
    """The largest of all ranks' values (-inf if none)."""
    return comm.allreduce(float(a.max()) if len(a) else -np.inf, op=MPI.MAX)


def successive_slides(times: np.ndarray, scarps: np.ndarray, h0: float,
                      min_retreat: float) -> dict:
    """Count the successive slides of a retrogressive failure (Section 4.5) from the
    back-scarp position at each snapshot.

    The scarp only retreats (its running minimum is taken, so debris flowing back does not
    count). Its retreat rate over each snapshot interval is compared with the run's own
    creep, the median rate over all intervals: a slide is a run of consecutive intervals
    retreating faster than twice that, with a total retreat of at least `min_retreat`.
    Where the scarp stands still between slides the median is 0 and any retreat counts;
    where it creeps between them (the K0 = 0.5 slope: 1.6-4.8 m/s, with bursts of
    11-14 m/s) only the bursts do.
    Returns the count, the time and new scarp position of each slide, and the threshold.
    """
    front = np.minimum.accumulate(scarps)
    rate = (front[:-1] - front[1:]) / np.maximum(np.diff(times), 1e-300)
    threshold = 2.0 * float(np.median(rate)) if len(rate) else 0.0
    slides = []
    start = None
    for k in range(1, len(front)):
        if rate[k - 1] > threshold:
            if start is None:
                start = k - 1
            continue
        if start is not None and front[start] - front[k - 1] >= min_retreat:
            slides.append((float(times[start + 1]), float(front[k - 1])))
        start = None
    if start is not None and front[start] - front[-1] >= min_retreat:
        slides.append((float(times[start + 1]), float(front[-1])))
    return {"slides": len(slides), "slide_times_s": [s[0] for s in slides],
            "slide_scarps_m": [s[1] for s in slides], "initial_height_m": h0,
            "slide_rate_threshold_m_per_s": threshold}


def slide_history(snaps: list[dict], dx: float) -> dict:
    """Back-scarp position at every snapshot and the successive slides it shows
    (`successive_slides`, a slide: a retreat of at least 5 dx)."""
    times = np.array([s["time"] for s in snaps])
    scarps = np.array([collapse_metrics(s["x"], s["x"] - s["u"], dx)["back_scarp_m"]
                       for s in snaps])
    h0 = collapse_metrics(snaps[0]["x"], snaps[0]["x"] - snaps[0]["u"], dx)["initial_height_m"]
    return slides_from(times, scarps, h0, dx)


SERIES_KEYS = ("time_s", "runout_m", "toe_m", "runout_spread_m", "final_height_m",
               "back_scarp_m", "plastic_work_J_per_m")


def series_block(snaps: list[dict], rows: list[dict]) -> dict:
    """`metrics.collapse` before the slides: the last snapshot's `collapse_metrics`, its
    dissipated plastic work sum_i w_i V_i (J/m; `plastic_work`), and `series`, one list
    a quantity over the snapshots (`SERIES_KEYS`; with the pressure quality's `rows` of a
    coupled run also the largest excess p and its 99th percentile over the particles).
    The excess p's peak is the largest over the snapshots, its final value the last
    snapshot's largest. The time resolution of the slide times is the longest snapshot
    interval (`slide_time_resolution_s`).
    snaps: per snapshot `collapse_metrics` plus time_s and plastic_work_J_per_m."""
    out = {k: v for k, v in snaps[-1].items() if k != "time_s"}
    series = {k: [s[k] for s in snaps] for k in SERIES_KEYS}
    if rows:
        series["excess_p_max_Pa"] = [r["excess_max_Pa"] for r in rows]
        series["excess_p_p99_Pa"] = [r["excess_p99_Pa"] for r in rows]
        out["excess_p_peak_Pa"] = max(series["excess_p_max_Pa"])
        out["excess_p_final_Pa"] = series["excess_p_max_Pa"][-1]
    times = np.asarray(series["time_s"])
    out["slide_time_resolution_s"] = float(np.diff(times).max()) if len(times) > 1 else 0.0
    out["series"] = series
    return out


def slides_from(times: np.ndarray, scarps: np.ndarray, h0: float, dx: float) -> dict:
    """`slide_history`'s block from the back-scarp series (s, m) and the initial height."""
    out = successive_slides(np.asarray(times), np.asarray(scarps), h0, 5 * dx)
    out.pop("initial_height_m")
    out["back_scarp_history_m"] = np.asarray(scarps).tolist()
    out["snapshot_times_s"] = np.asarray(times).tolist()
    return out


def collapse_verification(path, scene, comm) -> dict:
    """The `metrics` block of a collapse or slope run from its snapshots `path`
    (particles.h5): the collapse metrics of the last snapshot, the slides over all of
    them, the time series of the metrics (`series`: one entry a snapshot;
    docs/vv/metrics.md) and, for a coupled run, the pressure quality (Sections 4.4-4.5).
    Collective: each rank reads its share of each snapshot's rows in turn (no rank holds
    a snapshot or any array as long as the particle count; psph/verify/distributed.py)."""
    dx = scene.particles.dx
    coupled = scene.pressure.scheme != "none"
    names = ("id", "x", "u", "p", "stress") if coupled else ("x", "u")
    thickness = scene.domain.max[1] - scene.domain.min[1] if scene.dim == 3 else 1.0
    snaps, rows = [], []
    with h5py.File(path, "r") as f:
        for name in sorted(f["snapshots"]):
            g = f["snapshots"][name]
            work = all(k in g for k in ("plastic_work", "vol"))  # older files lack them
            snap = plane_strain_view(
                read_share(g, names + (("plastic_work", "vol") if work else ()), comm))
            snap["time"] = float(g.attrs["time"])
            m = collapse_metrics(snap["x"], snap["x"] - snap["u"], dx, comm)
            m["time_s"] = snap["time"]
            # dissipated plastic work per metre (plane strain; a 3D slab's over its
            # thickness), the same bits on any ranks
            m["plastic_work_J_per_m"] = exact_dot(snap["plastic_work"], snap["vol"], comm) \
                / thickness if work else None
            snaps.append(m)
            if coupled:
                rows.append(snapshot_quality(snap, scene, comm, checkerboard=scene.dim == 2))
    out = {"collapse": series_block(snaps, rows), "time_s": snaps[-1]["time_s"]}
    out["collapse"].update(slides_from(np.array(out["collapse"]["series"]["time_s"]),
                                       np.array(out["collapse"]["series"]["back_scarp_m"]),
                                       snaps[0]["initial_height_m"], dx))
    if coupled:
        out["pressure_quality"] = pressure_quality_from(rows, scene)
    return out

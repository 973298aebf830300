"""One particle's pore pressure against its neighbours, and the terms of Eq. (26) that
hold it there, from the snapshots of a run: the diagnosis of single-particle pressure
spikes in a disordered basal layer (`kernels/shifting.py`).

For the particle `id` at each snapshot (serial, numpy; walls mirrored as
`kernels/ghosts.py` does: positions mirrored, p shifted by the hydrostatic difference on an
impermeable wall or mirrored to -p on a drained one, velocities as on a free-slip wall):

- p and the mean p of its neighbours within 2h, its porosity;
- the kernel sum sum_j V_j W_ij (self included): 1 in a full, regular support, below 1
  where the particle sits in a sparse spot;
- S_i = sum_j V_j grad_i W_ij. The pair-symmetric Eq. (26) splits the pore pressure's
  acceleration into -p_i S_i / rho_i (the particle's own pressure, zero only where the
  support is symmetric) and -sum_j V_j p_j grad_i W_ij / rho_i (its neighbours'). Where
  S_i is not zero, the particle's own pressure is a force on it, and its equilibrium
  takes a pressure its neighbours do not have;
- div v with the plain kernel gradient and with the corrected one of Eq. (22) (the one
  Eq. 24-25 integrate).

`python -m psph.analysis.particle OUT ID [--from T0] [--to T1]` prints one row per snapshot.
Volumes are taken from the porosity with the solid volume kept, V = dx^2 (1 - n0) / (1 - n).

`python -m psph.analysis.particle OUT --bands [--from T0] [--to T1]` prints, per snapshot,
the particles of the bottom 0.6 m in bands of height above the floor (the regular bottom
row sits at dx/2), with the median, 99th percentile and largest of p minus the mean p of
each one's neighbours within 2h: where the single-particle spikes of the base are.
"""

from __future__ import annotations

import numpy as np

from psph.kernels.spline import dw_cubic, w_cubic
from psph.verify.pressure import neighbour_pairs


def _with_walls(snap: dict, scene) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Positions, velocities (free-slip mirror), pressures and row indices of the real
    particles and their wall mirrors (one mirror per wall; corners are not doubled)."""
    x, v, p = snap["x"], snap["v"], snap["p"]
    xs, vs, ps, rows = [x], [v], [p], [np.arange(len(x))]
    rho_l_b = scene.material.rho_l * np.asarray(scene.gravity, float)
    lo, hi = scene.domain.min, scene.domain.max
    for side, axis, pos in (("left", 0, lo[0]), ("right", 0, hi[0]),
                            ("bottom", 1, lo[1]), ("top", 1, hi[1])):
        wall = getattr(scene.boundaries, side)
        if wall.motion == "free":
            continue
        xg = x.copy()
        xg[:, axis] = 2.0 * pos - x[:, axis]
        vg = v.copy()
        vg[:, axis] = -v[:, axis]
        if wall.flow == "drained":
            pg = -p
        else:
            pg = p + (xg - x) @ rho_l_b
        xs.append(xg)
        vs.append(vg)
        ps.append(pg)
        rows.append(np.arange(len(x)))
    return np.vstack(xs), np.vstack(vs), np.concatenate(ps), np.concatenate(rows)


def particle_terms(snap: dict, pid: int, scene) -> dict:
    """The quantities of the module docstring for particle `pid` of one snapshot."""
    dx = scene.particles.dx
    h = scene.particles.h_factor * dx
    m = scene.material
    n = snap["n"]
    vol = dx * dx * (1.0 - m.porosity) / (1.0 - n)
    rho = (1.0 - n) * m.rho_s + n * m.rho_l
    xs, vs, ps, rows = _with_walls(snap, scene)
    i = int(np.searchsorted(snap["id"], pid))
    r = xs - xs[i]
    d = np.hypot(r[:, 0], r[:, 1])
    near = np.flatnonzero((d < 2.0 * h) & (d > 0.0))
    vj = vol[rows[near]]
    grad = np.array([dw_cubic(dd, h) for dd in d[near]])[:, None] * (-r[near]) / d[near, None]
    s_i = (vj[:, None] * grad).sum(axis=0)
    moment = (vj[:, None, None] * r[near][:, :, None] * grad[:, None, :]).sum(axis=0)
    gv = (vj[:, None, None] * (vs[near] - vs[i])[:, :, None] * grad[:, None, :]).sum(axis=0)
    real = near[near < len(n)]
    return {
        "time_s": float(snap["time"]), "y": float(xs[i, 1]), "x": float(xs[i, 0]),
        "p": float(ps[i]), "p_neighbours": float(ps[real].mean()) if len(real) else np.nan,
        "n": float(n[i]),
        "kernel_sum": float(vol[i] * w_cubic(0.0, h)
                            + sum(vv * w_cubic(dd, h) for vv, dd in zip(vj, d[near], strict=True))),
        "S": s_i.tolist(),
        "acc_own_p": (-ps[i] * s_i / rho[i]).tolist(),
        "acc_neighbours_p": (-(vj * ps[near])[:, None] * grad).sum(axis=0) / rho[i],
        "div_v_plain": float(np.trace(gv)),
        "div_v_corrected": float(np.trace(gv @ np.linalg.inv(moment))),
    }


BANDS_DX = (0.0, 0.3, 0.425, 0.575, 0.75, 1.125, 1.5)  # band edges in dx above the floor


def basal_bands(snap: dict, scene) -> list[dict]:
    """Per height band (`BANDS_DX`, in dx above the floor): particle count and the median,
    99th percentile and largest of p - (mean p of the other particles within 2h)."""
    dx = scene.particles.dx
    h = scene.particles.h_factor * dx
    x, p = snap["x"], snap["p"]
    i, j, _ = neighbour_pairs(x, 2.0 * h)
    count = np.bincount(i, minlength=len(p))
    mean = np.bincount(i, weights=p[j], minlength=len(p)) / np.maximum(count, 1)
    dev = np.where(count > 0, p - mean, np.nan)
    height = (x[:, 1] - scene.domain.min[1]) / dx
    rows = []
    for lo, hi in zip(BANDS_DX[:-1], BANDS_DX[1:], strict=True):
        sel = (height >= lo) & (height < hi) & np.isfinite(dev)
        d = dev[sel]
        rows.append({"band_dx": (lo, hi), "particles": int(sel.sum()),
                     "median_Pa": float(np.median(d)) if len(d) else None,
                     "p99_Pa": float(np.percentile(d, 99)) if len(d) else None,
                     "max_Pa": float(d.max()) if len(d) else None})
    return rows

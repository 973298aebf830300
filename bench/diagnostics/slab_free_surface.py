"""Which particles of a `collapse_saturated_3d` slab each 3D free-surface test flags,
against the 2D scene's test read in the slab's x-z plane (M_xx + M_zz < 1.5), snapshot by
snapshot (issue 37, docs/vv/collapse_saturated_3d.md, "The drained surface in 3D").

    python bench/diagnostics/slab_free_surface.py RUN [RUN ...]
    python bench/diagnostics/slab_free_surface.py --list RUN    # the differing sites

RUN is a slab's output directory (dx = 0.08 m, 4 dx thick, as the bench's `--dx 0.08`
runs). M of Eq. (22) is summed in numpy from the snapshot's positions and volumes, with
the mirror ghosts of the slip walls (front, back), the floor and the left wall, and of
the floor's corners with the front and back. The tests (M's eigenvalues l1 <= l2 <= l3):
the trace (< 2.25, psph until 2026-12-06), the two smallest eigenvalues (l1 + l2 < 1.5,
tried on 2026-12-06), the normal plus the tangents' mean ((trace + l1) / 2 < 1.5,
`psph/kernels/free_surface.py`) and the normal alone (l1 < 0.714, a lattice face's
threshold for 2D's trace). Printed: the x-z sites (4 particles each) that the x-z test
flags, and per test the sites it adds (+) and misses (-).
"""

import argparse
from pathlib import Path

import numpy as np

from psph.config.load import run_scene
from psph.io.snapshots import read_snapshots
from psph.kernels.spline import dw_cubic_dim

TESTS = {
    "trace < 2.25": lambda e: e.sum(axis=1) < 2.25,
    "l1 + l2 < 1.5": lambda e: e[:, 0] + e[:, 1] < 1.5,
    "(trace + l1) / 2 < 1.5": lambda e: 0.5 * (e.sum(axis=1) + e[:, 0]) < 1.5,
    "l1 < 0.714": lambda e: e[:, 0] < 0.714,
}


def moments(snap: dict, dx: float, width: float, h_factor: float) -> np.ndarray:
    """M (N, 3, 3) of every particle, its neighbours' mirror ghosts included."""
    x, vol = snap["x"], snap["vol"]
    h = h_factor * dx
    pts, vols = [x], [vol]
    for axis, plane in ((1, 0.0), (1, width), (2, 0.0), (0, 0.0)):
        near = np.abs(x[:, axis] - plane) < 2 * h
        g = x[near].copy()
        g[:, axis] = 2 * plane - g[:, axis]
        pts.append(g)
        vols.append(vol[near])
    for plane in (0.0, width):
        near = (np.abs(x[:, 1] - plane) < 2 * h) & (x[:, 2] < 2 * h)
        g = x[near].copy()
        g[:, 1] = 2 * plane - g[:, 1]
        g[:, 2] = -g[:, 2]
        pts.append(g)
        vols.append(vol[near])
    cloud, v = np.concatenate(pts), np.concatenate(vols)
    m = np.zeros((len(x), 3, 3))
    for i, xi in enumerate(x):
        d = cloud - xi
        r = np.linalg.norm(d, axis=1)
        near = (r > 1e-12) & (r < 2 * h)
        d, r = d[near], r[near]
        dw = np.array([dw_cubic_dim(rr, h, 3) for rr in r])
        grad = -dw[:, None] * d / r[:, None]  # grad_i W_ij, x_i - x_j = -d
        m[i] = (v[near, None] * d).T @ grad  # sum_j V_j x_ji (x) grad_i W_ij
    return m


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", type=Path, nargs="+")
    ap.add_argument("--list", action="store_true", help="print the differing sites")
    args = ap.parse_args()
    for out in args.runs:
        scene = run_scene(out)
        dx, width = scene.particles.dx, scene.domain.max[1] - scene.domain.min[1]
        for snap in read_snapshots(out / "particles.h5")[1:]:
            m = moments(snap, dx, width, scene.particles.h_factor)
            e = np.sort(np.linalg.eigvalsh(0.5 * (m + m.transpose(0, 2, 1))), axis=1)
            ref = m[:, 0, 0] + m[:, 2, 2] < 1.5
            line = f"{out.name:30s} {snap['time']:5.2f} x-z test: {ref.sum() // 4:3d} sites"
            for name, test in TESTS.items():
                t = test(e)
                line += f" | {name}: +{(t & ~ref).sum() // 4} -{(~t & ref).sum() // 4}"
            print(line, flush=True)
            if args.list:
                differ = np.zeros(len(ref), dtype=bool)
                for test in TESTS.values():
                    differ |= test(e) != ref
                for i in np.flatnonzero(differ):
                    if snap["x"][i, 1] < dx:  # one layer of the four
                        print(f"    x {snap['x'][i, 0]:.3f} z {snap['x'][i, 2]:.3f} "
                              f"M_xx + M_zz {m[i, 0, 0] + m[i, 2, 2]:.3f} "
                              f"M_yy {m[i, 1, 1]:.3f} l {np.round(e[i], 3)}")


if __name__ == "__main__":
    main()

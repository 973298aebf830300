"""The film of a collapse_3d run (issue 37, docs/vv/collapse_3d.md): the run-out against
Lube's law, the particles beyond 1.8 m (the deposit's body ends near 1.5-1.7 m at
a = 0.5), how many of them lie on the floor's plane and still move, and where they came
from (the column's rim at its base).

    python bench/diagnostics/collapse_3d_film.py RUN_DIR

A run with the floor as a surface lined with boundary particles, instead of the mirror
floor of the built-in scene:

    python -m psph run bench/diagnostics/collapse_3d_surface_floor.toml --out runs/c3d_surface

The variants of the floor's weight continuation (`kernels/boundary_3d.py`) apply
`surface_floor_no_weight.patch` or `surface_floor_compression_only.patch` to a worktree
(`git worktree add /tmp/x b844fca && git -C /tmp/x apply $PWD/bench/diagnostics/<patch>`:
the commit they were made on; they do not apply to later ones) and run the same scene
there with `PYTHONPATH=/tmp/x`.
"""

import json
import sys

import h5py
import numpy as np


def main(out: str) -> None:
    d = json.load(open(f"{out}/summary.json"))
    c = d.get("metrics", d.get("errors", {}))["collapse_3d"]
    print(f"run-out (r - r_i) / r_i = {c['runout_normalised']:.3f} (Lube "
          f"{c['lube_runout_normalised']:.2f}); 99.8th percentile radius by snapshot: "
          f"{[round(v, 2) for v in c['series']['runout_radius_m']]}; top "
          f"{c['final_height_m']:.3f} m")
    with h5py.File(f"{out}/particles.h5") as f:
        names = sorted(f["snapshots"])
        last = f["snapshots"][names[-1]]
        x, v, ids = last["x"][:], last["v"][:], last["id"][:]
        r = np.hypot(x[:, 0], x[:, 1])
        film = r > 1.8
        print(f"beyond 1.8 m: {film.sum()} of {len(r)}; on the floor's plane (z < 0.01 m): "
              f"{(film & (x[:, 2] < 0.01)).sum()}; moving faster than 0.3 m/s: "
              f"{(np.linalg.norm(v, axis=1) > 0.3).sum()}")
        if not film.any():
            return
        first = f["snapshots"][names[0]]
        born = np.isin(first["id"][:], ids[film])
        x0 = first["x"][:][born]
        print(f"they started at r = {np.hypot(x0[:, 0], x0[:, 1]).min():.2f}-"
              f"{np.hypot(x0[:, 0], x0[:, 1]).max():.2f} m, z = "
              f"{sorted(set(np.round(x0[:, 2], 3)))} m")
        for name in names:
            g = f["snapshots"][name]
            m = np.isin(g["id"][:], ids[film])
            xs, s, vs = g["x"][:][m], g["stress"][:][m], g["v"][:][m]
            rr = np.hypot(xs[:, 0], xs[:, 1])
            vr = (vs[:, 0] * xs[:, 0] + vs[:, 1] * xs[:, 1]) / rr
            print(f"  t = {g.attrs['time']:.2f} s: median z {np.median(xs[:, 2]):.3f} m, "
                  f"r {np.median(rr):.2f} m, v_r {np.median(vr):.2f} m/s, mean stress "
                  f"{np.median(s[:, :3].mean(axis=1)):.0f} Pa")


if __name__ == "__main__":
    main(sys.argv[1])

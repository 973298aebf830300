"""The saturated collapse's pressure and plastic fields, snapshot by snapshot, for runs of
the 2D scene and of the 3D slab side by side (issue 37, docs/vv/collapse_saturated_3d.md):
which of the two moves with dx, and whether the difference is the excess pressure's
tail or its bulk.

    python bench/diagnostics/collapse_saturated_fields.py RUN [RUN ...]

RUN is an output directory of `psph run collapse_saturated_psi<psi>` or of
`collapse_saturated_3d` (`bench/verification/collapse_saturated_3d.py` writes them under
runs/collapse_saturated_3d/). A slab is read in its x-z plane (`plane_strain_view`), as
the bench's metrics are. Per snapshot: the 50th, 95th and 99th percentiles of |excess p|
and the mean of the signed excess p (kPa), the mean accumulated plastic strain, the mean
porosity change and the share of particles that have yielded.
"""

import sys
from pathlib import Path

import numpy as np

from psph.config.load import run_scene
from psph.io.snapshots import read_snapshots
from psph.verify.collapse import plane_strain_view
from psph.verify.pressure import excess_pressure


def rows(out: Path) -> list[str]:
    scene = run_scene(out)
    snaps = read_snapshots(out / "particles.h5")
    n0 = dict(zip(snaps[0]["id"], snaps[0]["n"], strict=True))
    lines = []
    for snap in snaps[1:]:
        excess = excess_pressure(plane_strain_view(snap), scene)
        mag = np.abs(excess) / 1e3
        dn = snap["n"] - np.array([n0[i] for i in snap["id"]])
        lines.append(f"{out.name:34s} {snap['time']:5.2f} "
                     + " ".join(f"{np.percentile(mag, q):7.2f}" for q in (50, 95, 99))
                     + f" {excess.mean() / 1e3:7.2f} {snap['eps_p'].mean():8.4f} "
                     f"{dn.mean():+9.5f} {np.mean(snap['eps_p'] > 1e-4):7.3f}")
    return lines


def main() -> None:
    print(f"{'run':34s} {'t (s)':>5s} {'p50':>7s} {'p95':>7s} {'p99':>7s} {'mean ex':>7s} "
          f"{'eps_p':>8s} {'n - n0':>9s} {'yielded':>7s}   (|excess p| and mean excess: kPa)")
    for arg in sys.argv[1:]:
        print("\n".join(rows(Path(arg))))


if __name__ == "__main__":
    main()

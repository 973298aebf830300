"""The saturated collapse's pressure and plastic fields, snapshot by snapshot, for runs of
the 2D scene and of the 3D slab side by side (issue 37, docs/vv/collapse_saturated_3d.md):
which of the two moves with dx, and whether the difference is the excess pressure's
tail or its bulk.

    python bench/diagnostics/collapse_saturated_fields.py RUN [RUN ...]
    python bench/diagnostics/collapse_saturated_fields.py --tail RUN [RUN ...]
    python bench/diagnostics/collapse_saturated_fields.py --layers SLAB_RUN
    python bench/diagnostics/collapse_saturated_fields.py --regions RUN [RUN ...]

RUN is an output directory of `psph run collapse_saturated_psi<psi>` or of
`collapse_saturated_3d` (`bench/verification/collapse_saturated_3d.py` writes them under
runs/collapse_saturated_3d/). A slab is read in its x-z plane (`plane_strain_view`), as
the bench's metrics are. Per snapshot: the 50th, 95th and 99th percentiles of |excess p|
and the mean of the signed excess p (kPa), the mean accumulated plastic strain, the mean
porosity change, the share of particles that have yielded and the share that hold
p = 0 (the drained surface and the drained top layer).

`--tail`: where the 1 % of particles with the largest |excess p| sit (the medians of
their x and of their height z above the floor, x's range) and their sign.
`--layers` (a slab only): how far its y-layers have parted, per snapshot: the spread over
the layers of the particles that started at one x-z site (of x-z position, n and p) and
|u_y|; to round-off the slab is the 2D flow on the y-summed 3D kernel.
`--regions`: the mean signed excess p (kPa) of the particles grouped by where they
started (x from the back wall in 1 m bands, height in four bands), per snapshot, and the
mean speed: where two runs' excess pressures part.
"""

import argparse
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
                     f"{dn.mean():+9.5f} {np.mean(snap['eps_p'] > 1e-4):7.3f} "
                     f"{np.mean(snap['p'] == 0.0):7.3f}")
    return lines


def tail_rows(out: Path) -> list[str]:
    """Per snapshot: the medians of x and z of the top 1 % of |excess p|, x's range, and
    the share of them whose excess is positive."""
    scene = run_scene(out)
    lines = []
    for snap in read_snapshots(out / "particles.h5")[1:]:
        view = plane_strain_view(snap)
        excess = excess_pressure(view, scene)
        top = np.abs(excess) >= np.percentile(np.abs(excess), 99)
        x, z = view["x"][top, 0], view["x"][top, -1]
        lines.append(f"{out.name:34s} {snap['time']:5.2f} {np.median(x):7.2f} "
                     f"{x.min():6.2f}-{x.max():<6.2f} {np.median(z):7.3f} "
                     f"{np.mean(excess[top] > 0):7.2f}")
    return lines


X_BANDS = (1.0, 2.0, 3.0)  # m from the back wall x = 0
Z_BANDS = (0.25, 1.0, 1.75)  # m above the floor


def region_rows(out: Path) -> list[str]:
    """Per snapshot and initial x band: the mean signed excess p (kPa) in each initial
    height band (`X_BANDS`, `Z_BANDS`), and the snapshot's mean speed."""
    scene = run_scene(out)
    snaps = read_snapshots(out / "particles.h5")
    if snaps[0]["time"] != 0.0:
        raise SystemExit(f"{out}: --regions needs the run's t = 0 snapshot")
    first = plane_strain_view(snaps[0])["x"]
    xb = np.digitize(first[:, 0], X_BANDS)
    zb = np.digitize(first[:, -1], Z_BANDS)
    lines = []
    for snap in snaps[1:]:
        view = plane_strain_view(snap)
        excess = excess_pressure(view, scene) / 1e3
        speed = np.linalg.norm(view["v"], axis=1).mean()
        for i in range(len(X_BANDS) + 1):
            cells = " ".join(f"{excess[(xb == i) & (zb == j)].mean():7.2f}"
                             for j in range(len(Z_BANDS) + 1))
            lines.append(f"{out.name:34s} {snap['time']:5.2f} {i:>6d} {cells} {speed:7.3f}")
    return lines


def layer_rows(out: Path) -> list[str]:
    """Per snapshot, the 99th percentiles over the x-z sites of the spread over a site's
    y-layers of x-z position, n and p, and over the particles of |u_y|. The sites are
    read from the t = 0 snapshot (the lattice; `read_snapshots` orders rows by id)."""
    snaps = read_snapshots(out / "particles.h5")
    first = snaps[0]
    if first["time"] != 0.0 or first["x"].shape[1] != 3:
        raise SystemExit(f"{out}: --layers needs a 3D slab with its t = 0 snapshot")
    site = np.round(first["x"][:, [0, 2]] / 1e-6).astype(np.int64)
    group, size = np.unique(site, axis=0, return_inverse=True, return_counts=True)[1:]
    group = group.ravel()
    if size.min() != size.max() or size.min() < 2:
        raise SystemExit(f"{out}: the x-z sites hold {size.min()}-{size.max()} particles, "
                         "not one per y-layer each")

    def spread(values):
        hi = np.full(group.max() + 1, -np.inf)
        lo = np.full(group.max() + 1, np.inf)
        np.maximum.at(hi, group, values)
        np.minimum.at(lo, group, values)
        return hi - lo

    lines = []
    for snap in snaps[1:]:
        x, n, p, u = snap["x"], snap["n"], snap["p"], snap["u"]
        xz = np.hypot(spread(x[:, 0]), spread(x[:, 2]))
        lines.append(f"{out.name:34s} {snap['time']:5.2f} {np.percentile(xz, 99) * 1e3:9.4f} "
                     f"{np.percentile(spread(n), 99):9.2e} "
                     f"{np.percentile(spread(p), 99) / 1e3:9.4f} "
                     f"{np.percentile(np.abs(u[:, 1]), 99) * 1e3:9.4f}")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", type=Path)
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--tail", action="store_true", help="where the top 1 %% of |excess p| sits")
    mode.add_argument("--layers", action="store_true", help="how far a slab's layers parted")
    mode.add_argument("--regions", action="store_true",
                      help="mean excess p by where the particles started")
    args = ap.parse_args()
    if args.tail:
        print(f"{'run':34s} {'t (s)':>5s} {'x med':>7s} {'x range':>13s} {'z med':>7s} "
              f"{'share>0':>7s}   (the top 1 % of |excess p|; m)")
        make = tail_rows
    elif args.layers:
        print(f"{'run':34s} {'t (s)':>5s} {'x-z (mm)':>9s} {'n':>9s} {'p (kPa)':>9s} "
              f"{'|u_y| mm':>9s}   (p99 over the x-z sites of the spread over a site's layers; "
              "|u_y|: p99 over the particles)")
        make = layer_rows
    elif args.regions:
        bands = " ".join(f"{b:>7s}" for b in ("z<0.25", "<1", "<1.75", ">1.75"))
        print(f"{'run':34s} {'t (s)':>5s} {'x band':>6s} {bands} {'|v|':>7s}   (mean excess "
              "p, kPa, by initial height band; x bands 0-1, 1-2, 2-3, >3 m; |v|: mean, m/s)")
        make = region_rows
    else:
        print(f"{'run':34s} {'t (s)':>5s} {'p50':>7s} {'p95':>7s} {'p99':>7s} {'mean ex':>7s} "
              f"{'eps_p':>8s} {'n - n0':>9s} {'yielded':>7s} {'p = 0':>7s}   (|excess p| and "
              "mean excess: kPa)")
        make = rows
    for out in args.runs:
        print("\n".join(make(out)))


if __name__ == "__main__":
    main()

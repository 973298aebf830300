"""Where the plain kernel gradient misreads div v in a 3D collapse (issue 37,
docs/vv/collapse_3d.md): for one snapshot, each particle's velocity gradient from the
plain kernel gradient, L_p = sum_j V_j (v_j - v_i) (x) grad W_ij (the dry scenes' strain
rate with `stabilisation.corrected_strain_rate = false`), and from the corrected one of
Eq. (22), L_c = L_p M^-1, exact for linear fields. Their traces' difference, binned by
the particle's support (the trace of the moment matrix M: 3 in the bulk, about 1.5 at a
flat free surface), over the particles shearing at more than 0.5 /s and more than 2h
above the floor (whose boundary particles the snapshot does not hold). The symmetry
planes (`left`, `front` with `symmetry = true`, at the domain's low x and y) are mirrored as the
solver's ghosts are, so only free surfaces cut a support.

    .venv/bin/python bench/diagnostics/collapse_3d_div_v.py runs/collapse_3d_a3 [--snapshot 1]

Brute force over all pairs in chunks (numpy): about a minute for 19,000 particles.
"""

import argparse
from pathlib import Path

import h5py
import numpy as np

from psph.config.load import run_scene


def with_mirrors(x, v, vol, planes):
    """x, v, vol with the images across the symmetry planes ((axis, position) pairs), as
    the solver's mirror ghosts: the position and velocity components normal to a plane
    flip; across two planes, also the image of the image."""
    xs, vs, ws = [x], [v], [vol]
    for axis, at in planes:
        for k in range(len(xs)):
            xm, vm = xs[k].copy(), vs[k].copy()
            xm[:, axis] = 2.0 * at - xm[:, axis]
            vm[:, axis] *= -1.0
            xs.append(xm)
            vs.append(vm)
            ws.append(ws[k])
    return np.concatenate(xs), np.concatenate(vs), np.concatenate(ws)


def gradients(x, v, vol, h, n):
    """(L_p, M): the plain velocity gradient and the moment matrix, (n, 3, 3) each, of the
    cubic spline of Eq. (21) in 3D (support 2h), of the first n particles of x over all of
    x (the particles and their images)."""
    a = 3.0 / (2.0 * np.pi) / h ** 4
    lp = np.zeros((n, 3, 3))
    m = np.zeros((n, 3, 3))
    for i0 in range(0, n, 500):
        i1 = min(n, i0 + 500)
        d = x[None, :, :] - x[i0:i1, None, :]  # x_j - x_i
        r = np.linalg.norm(d, axis=2)
        q = r / h
        dw = np.where(q < 1, a * (-2 * q + 1.5 * q * q),
                      np.where(q < 2, -0.5 * a * (2 - q) ** 2, 0.0))
        with np.errstate(invalid="ignore", divide="ignore"):
            gw = np.where(r[..., None] > 0, -dw[..., None] * d / r[..., None], 0.0)
        w = np.broadcast_to(vol[None, :], (i1 - i0, len(x)))
        lp[i0:i1] = np.einsum("ij,ija,ijb->iab", w, v[None, :, :] - v[i0:i1, None, :], gw)
        m[i0:i1] = np.einsum("ij,ija,ijb->iab", w, d, gw)
    return lp, m


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("--snapshot", type=int, default=1, help="index of the snapshot")
    args = ap.parse_args()
    scene = run_scene(Path(args.run))
    h = scene.particles.h_factor * scene.particles.dx
    with h5py.File(f"{args.run}/particles.h5", "r") as f:
        name = sorted(f["snapshots"])[args.snapshot]
        g = f["snapshots"][name]
        x, v, vol = g["x"][:], g["v"][:], g["vol"][:]
        t = float(g.attrs["time"])
    planes = [(axis, scene.domain.min[axis]) for axis, side in enumerate(("left", "front"))
              if getattr(scene.boundaries, side) is not None
              and getattr(scene.boundaries, side).symmetry]
    lp, m = gradients(*with_mirrors(x, v, vol, planes), h, len(x))
    lc = lp @ np.linalg.inv(m)
    tr_p = np.trace(lp, axis1=1, axis2=2)
    tr_c = np.trace(lc, axis1=1, axis2=2)
    d = 0.5 * (lc + np.transpose(lc, (0, 2, 1)))
    d -= np.eye(3)[None] * (tr_c / 3)[:, None, None]
    shear = np.sqrt(2 * np.einsum("iab,iab->i", d, d))
    support = np.trace(m, axis1=1, axis2=2)
    flow = (shear > 0.5) & (x[:, 2] > 2 * h)
    print(f"{args.run}, t = {t:.3f} s: {len(x)} particles, {flow.sum()} shearing above 2h")
    print("| support tr M | particles | div v plain (1/s) | corrected (1/s) | plain - corrected"
          " | of the shear rate |")
    print("|---|---|---|---|---|---|")
    for lo, hi in ((0.0, 1.5), (1.5, 2.0), (2.0, 2.5), (2.5, 2.8), (2.8, 9.0)):
        sel = flow & (support >= lo) & (support < hi)
        if not sel.any():
            continue
        b = (tr_p - tr_c)[sel]
        print(f"| [{lo}, {hi}) | {sel.sum()} | {tr_p[sel].mean():+.4f} | {tr_c[sel].mean():+.4f}"
              f" | {b.mean():+.4f} | {np.mean(b / shear[sel]):+.4f} |")


if __name__ == "__main__":
    main()

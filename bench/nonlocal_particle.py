"""One particle's softening variables through a run with the non-local law (issue 17):
its local eps_p, the average eps_bar over 2 l_c, the over-non-local eps_hat = (1 - m)
eps_p + m eps_bar clipped at 0 (psph/kernels/nonlocal_strain.py), the dilation angle
Eq. (19) gives for eps_hat and for eps_p, and its porosity (Eq. 24), at every snapshot.

    .venv/bin/python bench/nonlocal_particle.py RUN ID [ID ...]

eps_bar is recomputed from the snapshot (all particles of the particle's material within
2 l_c and their images across the walls, the cubic spline of Eq. (21), volume weights),
as the kernel does each step. Shows why `retrogressive_k0_0.5` with l_c = 1.2 m at
dx = 0.566 m stopped with a porosity of 0 while psi decayed with eps_hat (README
"Convergence of the landslide answers").
"""

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).parent.parent
sys.path.insert(0, str(ROOT))

from psph.io.snapshots import read_snapshots  # noqa: E402
from psph.kernels.spline import w_cubic  # noqa: E402
from psph.scene import run_scene  # noqa: E402

SIDES = {"left": (0, 0), "right": (0, 1), "bottom": (1, 0), "top": (1, 1)}


def mirrors(x: np.ndarray, walls: list[tuple[int, float]]) -> list[np.ndarray]:
    """x, its images across each wall (axis, position) and across two walls of different
    axes (a corner), as `nonlocal_strain` sums them."""
    out = [x]
    for k, (ax, pos) in enumerate(walls):
        y = x.copy()
        y[:, ax] = 2.0 * pos - y[:, ax]
        out.append(y)
        for bx, pos_b in walls[k + 1:]:
            if bx != ax:
                z = y.copy()
                z[:, bx] = 2.0 * pos_b - z[:, bx]
                out.append(z)
    return out


def history(run: Path, pid: int) -> list[dict]:
    """Per snapshot: time, position, eps_p, eps_bar, eps_hat, psi (deg) from eps_hat and
    from eps_p, and porosity of particle `pid`."""
    scene = run_scene(run)
    mats = scene.material_list
    walls = [(axis, (scene.domain.min, scene.domain.max)[end][axis])
             for side, (axis, end) in SIDES.items()
             if getattr(scene.boundaries, side).motion != "free"]
    rows = []
    for s in read_snapshots(run / "particles.h5"):
        hit = np.flatnonzero(s["id"] == pid)
        if not len(hit):
            continue
        i = int(hit[0])
        mat = mats[int(s["material"][i])]
        reg = mat.plasticity.regularisation
        if reg is None:
            raise SystemExit(f"{run}: material {mat.name!r} has no regularisation")
        lc, m = reg.length, reg.m
        x = s["x"]
        d = np.linalg.norm(x - x[i], axis=1)
        near = np.flatnonzero((d < 2.0 * lc) & (s["material"] == s["material"][i]))
        num = den = 0.0
        for images in mirrors(x[near], walls):
            r = np.linalg.norm(images - x[i], axis=1)
            w = s["vol"][near] * np.array([w_cubic(q, lc) if q < 2.0 * lc else 0.0
                                           for q in r])
            num += float(w @ s["eps_p"][near])
            den += float(w.sum())
        bar = num / den
        hat = max((1.0 - m) * s["eps_p"][i] + m * bar, 0.0)
        psi0, s_f = mat.plasticity.psi, mat.plasticity.s_f
        rows.append({"time_s": float(s["time"]), "x": x[i].tolist(),
                     "eps_p": float(s["eps_p"][i]), "eps_bar": bar, "eps_hat": hat,
                     "psi_hat_deg": psi0 * math.exp(-s_f * hat),
                     "psi_local_deg": psi0 * math.exp(-s_f * s["eps_p"][i]),
                     "n": float(s["n"][i])})
    return rows


def main(argv: list[str]) -> int:
    if len(argv) < 2:
        print(__doc__)
        return 2
    run = Path(argv[0])
    for pid in map(int, argv[1:]):
        print(f"{run}, particle {pid}")
        print(f"  {'t s':>5s} {'x m':>8s} {'y m':>6s} {'eps_p':>7s} {'eps_bar':>7s} "
              f"{'eps_hat':>7s} {'psi(hat)':>8s} {'psi(eps_p)':>10s} {'n':>6s}")
        for r in history(run, pid):
            print(f"  {r['time_s']:5.1f} {r['x'][0]:8.2f} {r['x'][1]:6.3f} {r['eps_p']:7.2f} "
                  f"{r['eps_bar']:7.2f} {r['eps_hat']:7.2f} {r['psi_hat_deg']:8.2f} "
                  f"{r['psi_local_deg']:10.2g} {r['n']:6.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

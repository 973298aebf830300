"""One particle's softening variables through a run with the non-local law (issue 17):
its local eps_p, the average eps_bar over 2 l_c, the over-non-local eps_hat = (1 - m)
eps_p + m eps_bar clipped at 0 (psph/kernels/nonlocal_strain.py), the dilation angle
Eq. (19) gives for eps_hat and for eps_p, and its porosity (Eq. 24), at every snapshot.

    python bench/diagnostics/nonlocal_particle.py RUN ID [ID ...]

eps_bar and eps_hat are computed from the snapshot by the solver's kernel
(`nonlocal_strain`, with the walls' images), as each step does. Shows why
`retrogressive_k0_0.5` with l_c = 1.2 m at dx = 0.566 m stopped with a porosity of 0
while psi decayed with eps_hat (README "Convergence of the landslide answers").
"""

import math
import sys
from pathlib import Path

import numpy as np

from psph.config.boundaries import plane_walls
from psph.config.load import run_scene
from psph.io.snapshots import read_snapshots
from psph.verify.nonlocal_average import nonlocal_strains

ROOT = Path(__file__).resolve().parents[2]


def averages_of(snapshot: dict, i: int, lengths: np.ndarray, weights: np.ndarray,
                walls) -> tuple[float, float]:
    """(eps_bar, eps_hat) of row i of a snapshot from the kernel `nonlocal_strain` (all
    rows real; row i moved first, the only owned one), one set of cell lists for both."""
    n = len(snapshot["id"])
    rows = np.r_[i, np.delete(np.arange(n), i)]
    bar, hat = nonlocal_strains(snapshot["x"][rows], snapshot["vol"][rows],
                                snapshot["eps_p"][rows], lengths,
                                [np.ones_like(weights), weights],
                                material=snapshot["material"][rows], n_owned=1,
                                walls=list(zip(walls.axis.tolist(), walls.pos.tolist(),
                                               strict=True)))
    return float(bar[0]), float(hat[0])


def history(run: Path, pid: int) -> list[dict]:
    """Per snapshot: time, position, eps_p, eps_bar, eps_hat, psi (deg) from eps_hat and
    from eps_p, and porosity of particle `pid`."""
    scene = run_scene(run)
    mats = scene.material_list
    walls = plane_walls(scene.boundaries, scene.domain.min, scene.domain.max)
    regs = [m.plasticity.regularisation if m.plasticity is not None else None for m in mats]
    lengths = np.array([r.length if r is not None else 0.0 for r in regs])
    weights = np.array([r.m if r is not None else 1.0 for r in regs])
    rows = []
    for s in read_snapshots(run / "particles.h5"):
        hit = np.flatnonzero(s["id"] == pid)
        if not len(hit):
            continue
        i = int(hit[0])
        k = int(s["material"][i])
        mat = mats[k]
        if regs[k] is None:
            raise SystemExit(f"{run}: material {mat.name!r} has no regularisation")
        bar, hat = averages_of(s, i, lengths, weights, walls)
        psi0, s_f = mat.plasticity.psi, mat.plasticity.s_f
        rows.append({"time_s": float(s["time"]), "x": s["x"][i].tolist(),
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

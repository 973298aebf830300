"""Issue 16: what the wall ghosts' new stress rule changes in other scenes. Runs a built-in
scene twice on one rank, with the ghosts as they were (every normal component of sigma'
mirrored, `oddeven_stress_mode.mirror_ghosts`) and as they are (the wall-normal total
stress continued with its weight, psph/kernels/ghosts.py), and prints both and their
largest particle-by-particle differences; `sliding` prints the table of
`python -m psph.app.sliding` under the old rule (compare with the module as it is).

usage (from the worktree): .venv/bin/python bench/diagnostics/ghost_stress_rule.py
  SCENE END | sliding

Outcome (2026-11-30, serial):
  collapse_saturated_psi0 0.3 (test_collapse's window; 2 min a rule):
    mirror     front x 4.0933 m, max|u| 0.1133 m, p -4.4 .. 14.7 kPa
    continued  front x 4.0911 m, max|u| 0.1111 m, p -4.5 .. 14.7 kPa
    largest differences: position 5.2 mm, p 1.5 kPa, sigma' 36 kPa
  sliding (scene settings; traction / strength / bottom-row excess / min excess, kPa):
    mirror 8.35 / 8.42 / -6.6 / -68.7, continued 8.33 / 8.41 / -8.5 / -67.0; every
    bottom-row excess 1.9-2.1 kPa more negative (the mirror's bottom row sank and
    compressed the base), sliding minus rest +0.5 kPa under both
  TPI-gravity map (`bench/verification/tpi_gravity.py`, geostatic column): unchanged, cell for cell
"""
import sys
from pathlib import Path

import numpy as np
from mpi4py import MPI

from psph.app.run import make_slabs
from psph.config.load import load_scene
from psph.solver.simulation import Simulation

PLAIN = Simulation._ghosts


def _mirrored(self):
    PLAIN(self)
    st = self.store
    g0, g1 = st.n_real, st.n_real + st.n_ghost
    st.stress[g0:g1, :3] = st.stress[self.ghost_src[g0:g1], :3]


def compare(name: str, end: float) -> None:
    res = {}
    for rule in ("mirror", "continued"):
        Simulation._ghosts = _mirrored if rule == "mirror" else PLAIN
        scene = load_scene(name, [f"time.end={end}"])
        sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
        sim.equilibrate()
        while sim.t < end - 1e-12:
            sim.advance_one()
        st = sim.store
        n = st.n_owned
        o = np.argsort(st.key[:n])
        res[rule] = (st.x[:n][o].copy(), st.p[:n][o].copy(), st.stress[:n][o].copy())
        print(f"{name} {rule:9s} t {sim.t:.3f}: front x {st.x[:n, 0].max():.4f} m, "
              f"max|u| {np.abs(st.u[:n]).max():.4f} m, p {st.p[:n].min() / 1e3:.1f} .. "
              f"{st.p[:n].max() / 1e3:.1f} kPa", flush=True)
    Simulation._ghosts = PLAIN
    (xa, pa, sa), (xb, pb, sb) = res["mirror"], res["continued"]
    print(f"  largest differences: position {np.abs(xa - xb).max():.2e} m, p "
          f"{np.abs(pa - pb).max() / 1e3:.2f} kPa, sigma' {np.abs(sa - sb).max() / 1e3:.2f} kPa")


if __name__ == "__main__":
    if sys.argv[1:] == ["sliding"]:
        Simulation._ghosts = _mirrored
        from psph.app.sliding import main

        main([])
    elif len(sys.argv) == 3 and Path(sys.argv[1]).suffix == "":
        compare(sys.argv[1], float(sys.argv[2]))
    else:
        sys.exit(__doc__)

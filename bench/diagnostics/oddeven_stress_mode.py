"""Issue 16 experiment: what excites the odd-even (zig-zag) mode of sigma' in a column at
rest under gravity (the two-layer column of `tests/test_materials.py`: 0.4 m x 2 m,
dx = 0.05, rho 2072.5 below y = 1 m and 1400 above, K0 = 0.5, water table 1.975, explicit
pressure, fixed bottom, slip sides, 0.05 s). Each variant removes one candidate exciter.
The reference is the initial state, which is the analytic (layered) overburden at the
particle centres to 1e-9. Errors in % of the base sigma'_v: "raw" per particle, "paired"
the mean of vertically adjacent particles (takes the zig-zag out), "@0.005" the raw error
after the first 0.005 s, "acc0" the largest |a_y| of the first step (m/s^2) and its row.

usage (from the worktree): .venv/bin/python bench/diagnostics/oddeven_stress_mode.py
  [VARIANT ...]   (default: all; each 8-20 s on one core)

Outcome (2026-11-30, serial; "mirror" = the ghosts as before the fix, every normal
component of sigma' copied; the others run the code as it is):

  variant                     raw %  at y   paired %  @0.005  p %    acc0 m/s^2 (row)
  layered_mirror              2.319  0.075  0.662     2.385   0.136  2.68 (0.025)
  uniform_mirror              1.542  0.075  0.173     1.628   0.146  2.68 (0.025)
  layered_mirror_equilibrate  2.217  0.025  0.718     2.218   0.002  (gravity loading 0.05 s)
  layered                     0.866  1.975  0.651     0.815   0.047  1.25 (1.025)
  uniform                     0.309  1.975  0.147     0.330   0.002  0.28 (1.975)
  uniform_top_wall            0.000  -      0.000     0.000   0.000  0.00 (a slip lid)
  layered_top_wall            1.006  0.925  0.639     0.814   0.190  1.25 (1.025)
  geostatic_mirror (0.2 s)    1.483  0.075  0.163     1.643   0.069  2.68 (0.025)
  geostatic (0.2 s)           0.309  1.975  0.147     0.332   0.000  0.28 (1.975)

  (uniform: both layers dense, as the built-in geostatic_column but for 0.05 s; K0 ratio,
  |v| and |u| at the end are printed too)

Verdicts:
  (a) the fixed bottom's mirror ghosts: CONFIRMED, the main exciter. A mirrored sigma'_nn
      has a kink at the wall: the bottom row lacks (rho - rho_l) g dx of support and sinks
      at 2.68 m/s^2 at t = 0 (the second row at 0.15). Within the first 0.005 s (one pass
      of the wave) the column settles into a static equilibrium whose sigma' carries a
      zig-zag from the bottom up (2.3 % / 1.5 % raw in the two-layer / one-density column),
      which Eq. (26) cannot see and nothing damps afterwards. Fixed in
      psph/kernels/ghosts.py: a ghost's wall-normal total stress is the real particle's
      plus the weight of the soil between them (the equilibrium gradient, as the ghost's p
      carries the hydrostatic one), so a geostatic sigma' stays linear across the wall:
      the one-density column 1.542 -> 0.309 % raw (the top row; 0.003 % below 1.9 m), and
      with a slip lid instead of the free surface it does not move at all (0.000 %).
  (a') the density jump at y = 1 m: CONFIRMED, the second exciter, inherent to Eq. (26)
      at a sharp jump: the pair sum averages the stress gradient over 2h across the jump
      while the particle divides it by its own rho_i, so the analytic state leaves
      -0.84 / +1.25 m/s^2 on the rows either side (-0.05 / +0.07 one row further). Their
      alternating sum is not zero, so the discrete equilibrium holds a zig-zag step of
      ~0.65 % of the base stress across the jump (below it with the mirror bottom, above it
      now, below it again with a lid). Not removed: an initial state in discrete
      equilibrium would be this state; gravity loading (`initial.equilibrate`) reaches it
      too and keeps the zig-zag (layered_mirror_equilibrate: 2.2 %).
  (b) the top free surface's cut support: a local error of the top row (0.31 % of the
      base stress in the one-density column, no zig-zag; +-0.28 m/s^2 on the two top rows
      at t = 0). A slip lid, whose ghosts continue sigma' linearly, takes it out
      (uniform_top_wall).
  (c) the pressure-momentum coupling: REFUTED. With both ends continued (uniform_top_wall)
      the coupled column stays at rest to round-off; the first step's accelerations are
      zero on every row but the bottom, interface and top ones.
  A dry variant of the column (pressure.scheme = "none") was dropped: at this scene's
  alpha_Pi = 0.1 it blows up within 0.05 s under either ghost rule (|v| 7 m/s), the known
  instability of a dry column at rest that the dry collapse meets with alpha_Pi = 1
  (README, "Dry column collapse").
"""
import sys

import numpy as np
from mpi4py import MPI
from two_layer_column import LAYERED, row_pairs

from psph.app.run import make_slabs
from psph.config.load import load_scene
from psph.solver.simulation import Simulation

VARIANTS = ["layered_mirror", "uniform_mirror", "layered_mirror_equilibrate", "layered",
            "uniform", "uniform_top_wall", "layered_top_wall", "geostatic_mirror", "geostatic"]


def scene_text(variant: str) -> str:
    text = LAYERED
    if variant.startswith("uniform"):
        text = text.replace('material = "light"', 'material = "dense"')
    if "dry" in variant:
        text = text.replace('scheme = "explicit"\ndrained_boundary = "layer"', 'scheme = "none"')
        text = text.replace("water_table = 1.975\n", "")
    if "top_wall" in variant:
        text = text.replace('top = { motion = "free", flow = "drained" }',
                            'top = { motion = "slip" }')
    if "equilibrate" in variant:
        text = text.replace("k0 = 0.5\n", "k0 = 0.5\nequilibrate = 0.05\n")
    return text


def mirror_ghosts(sim: Simulation) -> None:
    """The ghosts as before the fix: every normal component of sigma' copied from the real
    particle (psph/kernels/ghosts.py then kept only the shear rule)."""
    plain = sim._ghosts

    def ghosts():
        plain()
        st = sim.store
        g0, g1 = st.n_real, st.n_real + st.n_ghost
        st.stress[g0:g1, :3] = st.stress[sim.ghost_src[g0:g1], :3]

    sim._ghosts = ghosts
    next(s for s in sim.stages if s.name == "ghosts").run = ghosts


def run(variant: str, end: float = 0.05) -> dict:
    if variant.startswith("geostatic"):  # the built-in scene as tests/test_geostatic.py
        scene, end = load_scene("geostatic_column", ["time.end=0.2"]), 0.2
    else:
        path = f"/tmp/oddeven_{variant}.toml"
        with open(path, "w") as f:
            f.write(scene_text(variant))
        scene = load_scene(path)
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
    if "mirror" in variant or "equilibrate" in variant:
        mirror_ghosts(sim)
    st = sim.store
    n = st.n_owned
    x0, y0 = st.x[:n].T.copy()
    sv0, p0 = st.stress[:n, 1].copy(), st.p[:n].copy()  # the analytic state (1e-9)
    base = np.abs(sv0).max()
    sim.equilibrate()
    sim.advance_one()
    acc0 = np.abs(st.acc[:n, 1])
    out = {"acc0": acc0.max(), "acc0_y": y0[acc0.argmax()]}
    early = None
    while sim.t < end - 1e-12:
        sim.advance_one()
        if early is None and sim.t >= 0.005 - 1e-12:
            early = np.abs(st.stress[:n, 1] - sv0).max() / base
    raw = np.abs(st.stress[:n, 1] - sv0) / base
    pair = np.abs(row_pairs(st.stress[:n, 1], x0, y0) - row_pairs(sv0, x0, y0)) / base
    pmax = p0.max()
    out.update(raw=raw.max(), raw_y=y0[raw.argmax()], paired=pair.max(), early=early,
               p=np.abs(st.p[:n] - p0).max() / pmax if pmax > 0 else 0.0,
               v=np.abs(st.v[:n]).max(), u=np.abs(st.u[:n]).max(),
               k0=np.abs(st.stress[:n, 0] / st.stress[:n, 1] - 0.5).max() / 0.5)
    rows = np.unique(np.round(y0, 9))
    out["rows"] = [(r, 100 * ((st.stress[:n, 1] - sv0) / base)[np.isclose(y0, r)].mean())
                   for r in rows]
    return out


def main(argv):
    variants = argv or VARIANTS
    print(f"{'variant':20s} {'raw %':>7s} {'at y':>6s} {'paired %':>9s} {'@0.005':>7s} "
          f"{'p %':>6s} {'acc0':>6s} (row)   |v| end  |u| end  K0 %")
    for v in variants:
        r = run(v)
        print(f"{v:20s} {100 * r['raw']:7.3f} {r['raw_y']:6.3f} {100 * r['paired']:9.3f} "
              f"{100 * r['early']:7.3f} {100 * r['p']:6.3f} {r['acc0']:6.2f} "
              f"({r['acc0_y']:.3f}) {r['v']:.1e} {r['u']:.1e} {100 * r['k0']:.3f}", flush=True)
        if len(variants) == 1:  # the error row by row (% of the base stress)
            for y, e in r["rows"]:
                print(f"  y = {y:.3f}  {e:8.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])

"""Per-term budget of d sigma_yy/dt for the middle particles of the bottom row of the
thin_layer_friction scene (one rank). Usage:
  python bench/diagnostics/thin_terms.py [rows] [theta] [steps] [--set key=value ...]
The terms (2D, dry, plain gradient as in update.advance): lam*l00, (lam+2mu)*l11,
spin -2 w sxy, plastic (after - elastic trial)/dt; cumulated over time and averaged over
the bottom row's particles with 1 < x < 3."""
import math
import os
import sys
import tomllib

import numpy as np
from mpi4py import MPI

sys.path.insert(0, "bench/diagnostics")
from thin_layer_friction import DX, SCENE  # noqa: E402

from psph.app.run import make_slabs  # noqa: E402
from psph.config.load import apply_override, resolve, validate  # noqa: E402
from psph.kernels.sum_columns import (  # noqa: E402
    GS_XX,
    GS_XY,
    GS_YX,
    GS_YY,
    GV_XX,
    GV_XY,
    GV_YX,
    GV_YY,
    M_XX,
    M_XY,
    M_YX,
    M_YY,
)
from psph.solver.simulation import Simulation  # noqa: E402

args = [a for a in sys.argv[1:] if "=" not in a]
sets = [a for a in sys.argv[1:] if "=" in a]
rows = int(args[0]) if args else 1
theta = float(args[1]) if len(args) > 1 else 15.0
steps = int(args[2]) if len(args) > 2 else 1500
g = 9.81
text = SCENE.format(gx=g * math.sin(math.radians(theta)), gz=-g * math.cos(math.radians(theta)),
                    dx=DX, h=rows * DX, c=100.0, end=0.5)
raw = tomllib.loads(text)
for assignment in sets:
    apply_override(raw, assignment)  # as `psph run --set`
scene = resolve(validate(raw))
sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
st = sim.store
lam = sim.mat[0, 0]
mu = sim.mat[0, 1]
n = st.n_owned
x0 = st.x[:n].copy()
sel = np.flatnonzero((x0[:, 0] > 1.0) & (x0[:, 0] < 3.0) & (x0[:, 1] < DX))
keys = st.key[:n][sel].copy()
print(f"h = {sim.h}, dt = {sim.stepping.dt_main:.3e}, lam {lam:.3e} mu {mu:.3e}, "
      f"{len(sel)} particles, artificial_stress {scene.stabilisation.artificial_stress}, "
      f"corrected {scene.stabilisation.corrected_strain_rate}")
upd = next(s for s in sim.stages if s.name.startswith("update"))
orig = upd.run
cum = np.zeros(5)  # l00, l11, spin, plastic, total
rec = {}
cum_div = np.zeros(1)


def wrapped():
    n = st.n_owned
    idx = np.flatnonzero(np.isin(st.key[:n], keys))
    s = sim.sums[idx]
    det = s[:, M_XX] * s[:, M_YY] - s[:, M_XY] * s[:, M_YX]
    l00 = s[:, GV_XX] + s[:, GS_XX]
    l11 = s[:, GV_YY] + s[:, GS_YY]
    l01 = s[:, GV_XY]
    l10 = s[:, GV_YX]
    mode = int(os.environ.get("PSPH_NORMAL_MODE", "0"))
    if mode == 2:
        l00 = l00 / s[:, M_XX]
        l11 = l11 / s[:, M_YY]
    elif mode == 1 or scene.stabilisation.corrected_strain_rate or scene.pressure.scheme != "none":
        m00, m01, m10, m11 = (s[:, M_YY] / det, -s[:, M_XY] / det, -s[:, M_YX] / det,
                              s[:, M_XX] / det)
        gs00, gs11 = l00.copy(), l11.copy()
        l00 = gs00 * m00 + (s[:, GV_XY] + s[:, GS_XY]) * m10
        l11 = (s[:, GV_YX] + s[:, GS_YX]) * m01 + gs11 * m11
        if scene.stabilisation.corrected_strain_rate:
            l01 = s[:, GV_XX] * m01 + s[:, GV_XY] * m11
            l10 = s[:, GV_YX] * m00 + s[:, GV_YY] * m10
    w = 0.5 * (l01 - l10)
    if os.environ.get("PSPH_NO_SPIN", "0") == "1":
        w = 0.0 * w
    sig = st.stress[idx].copy()
    dt = sim.dt
    t_l00 = lam * l00
    t_l11 = (lam + 2 * mu) * l11
    t_spin = -2.0 * w * sig[:, 3]
    trial = sig[:, 1] + dt * (t_l00 + t_l11 + t_spin)
    orig()
    after = st.stress[idx, 1]
    t_pl = (after - trial) / dt
    terms = np.array([t_l00.mean(), t_l11.mean(), t_spin.mean(), t_pl.mean(), 0.0])
    terms[4] = terms[:4].sum()
    cum[:] += dt * terms
    rec.update(l00=l00.mean(), l11=l11.mean(), l01=l01.mean(), l10=l10.mean(),
               myy=s[:, M_YY].mean(), y=st.x[idx, 1].mean(), vx=st.v[idx, 0].mean(),
               vy=st.v[idx, 1].mean(), syy=after.mean(), sxx=st.stress[idx, 0].mean(),
               sxy=st.stress[idx, 3].mean(), szz=st.stress[idx, 2].mean(),
               eps=st.eps_p[idx].mean(), mxx=s[:, M_XX].mean(),
               div=(l00 + l11).mean(), mean=st.stress[idx, :3].sum(axis=1).mean() / 3,
               slope=np.polyfit(st.x[idx, 0], st.v[idx, 0], 1)[0])
    cum_div[0] += dt * rec["div"]


upd.run = wrapped
print("  step   t(s)   y/dx   v_x     v_y     sxx     syy     szz     sxy  | cumulative "
      "d syy: lam*l00  (l+2m)*l11  spin  plastic  total | l11(1/s) l01 M_yy eps_p")
for k in range(steps):
    sim.advance_one()
    if k in (0, 5, 20, 100, 150, 200, 250, 300, 400, 550, 700, 1000, 1499) or k == steps - 1:
        r = rec
        print(f"{k:6d} {sim.t:6.3f} {r['y'] / DX:6.3f} {r['vx']:7.4f} {r['vy']:8.5f} "
              f"{r['sxx']:7.1f} {r['syy']:7.1f} {r['szz']:7.1f} {r['sxy']:7.1f} | "
              f"{cum[0]:8.1f} {cum[1]:8.1f} {cum[2]:8.1f} {cum[3]:8.1f} {cum[4]:8.1f} | "
              f"{r['l11']:9.2e} {r['l01']:9.2e} {r['myy']:.3f} {r['eps']:.2e}")
        print(f"{'':14s} mean {r['mean']:7.1f}  l00 {r['l00']:9.2e}  M_xx {r['mxx']:.3f}  "
              f"row dvx/dx {r['slope']:9.2e}  div v {r['div']:9.2e}  cum div {cum_div[0]:9.2e}")

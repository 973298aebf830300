"""Issue 16 experiment: a saturated layer at rest on a polyline (dipping with lattice steps,
or horizontal at a chosen offset below a lattice row); excess p after t = 0.
usage (from the worktree, PYTHONPATH=. so that its psph is imported):
  polyline_dip_pressure.py VARIANT OUT [MOTION [EQUILIBRATE [KEY=VALUE ...]]]
  VARIANT: dip | flat_dx | flat_short | flat_long"""
import sys

import numpy as np
from mpi4py import MPI

from psph.app.run import run
from psph.config.load import load_scene
from psph.io.snapshots import read_snapshots
from psph.verify.pressure import excess_pressure

SCENE = """
name = "dip_{v}"
gravity = [0.0, -9.81]
[domain]
min = [0.0, 0.0]
max = [40.0, 8.0]
[particles]
dx = 0.5
[[particles.layers]]
top = [[0.0, 6.0], [40.0, 6.0]]
bottom = {line}
[material]
model = "elastic"
E = 60.0e6
nu = 0.3
porosity = 0.3
rho_s = 2700.0
k = 1.0e-6
K_l = 1.0e8
[[boundaries.polylines]]
points = {line}
soil = "above"
motion = "{motion}"
{extra}
[boundaries]
left = {{ motion = "slip" }}
right = {{ motion = "slip" }}
[initial]
water_table = 6.0
k0 = 0.5
equilibrate = {eq}
[pressure]
scheme = "explicit"
ponding = true
[time]
integrator = "symplectic"
dt = 4.0e-4
allow_dt_above_solid_limit = true
end = {end}
[output]
interval = 0.1
"""
LINES = {"dip": "[[-1.0, 2.0349], [41.0, 0.5676]]",  # 2 degrees
         "flat_dx": "[[-1.0, 2.0], [41.0, 2.0]]",     # lowest row 2.25: gap dx
         "flat_short": "[[-1.0, 2.24], [41.0, 2.24]]",  # gap 0.52 dx
         "flat_long": "[[-1.0, 2.26], [41.0, 2.26]]"}   # lowest row 2.75: gap 1.48 dx
v, out = sys.argv[1], sys.argv[2]
motion = sys.argv[3] if len(sys.argv) > 3 else "friction"
eq = sys.argv[4] if len(sys.argv) > 4 else "1.0"
sets = sys.argv[5:]
extra = 'friction_angle = 20.0' if motion == "friction" else ""
text = SCENE.format(v=v, line=LINES[v], motion=motion, extra=extra, eq=eq, end=0.4)
f = f"/tmp/dip_{v}.toml"
open(f, "w").write(text)
scene = load_scene(f, sets)
run(scene, out, comm=MPI.COMM_SELF, quiet=True)
for s in read_snapshots(f"{out}/particles.h5"):
    ex = excess_pressure(s, scene) / 1e3
    z0 = s["x"][:, 1] - s["u"][:, 1]
    zl = np.interp(s["x"][:, 0] - s["u"][:, 0], *np.array(eval(LINES[v])).T)
    base = (z0 - zl) < 1.5 * 0.5
    print(f"{out} {v} {motion} t={s['time']:.2f} excess p kPa: all {ex.min():8.1f} "
          f"{ex.max():8.1f}  base rows {ex[base].min():8.1f} {ex[base].max():8.1f}"
          f"  |u|max {np.abs(s['u']).max():.2e}")

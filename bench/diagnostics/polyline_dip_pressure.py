"""A saturated layer at rest on a polyline (dipping with lattice steps, or horizontal at a
chosen offset below a lattice row); excess p after t = 0 (the boundary particles' pressure,
docs/vv/boundary_particles.md).
usage (from the worktree, PYTHONPATH=. so that its psph is imported):
  polyline_dip_pressure.py VARIANT OUT [MOTION [EQUILIBRATE [KEY=VALUE ...]]]
  VARIANT: dip | flat_dx | flat_short | flat_long
The scene is tests/scenes/dipping_base.toml with this experiment's own choices: the
VARIANT's line as the layer's bottom and the polyline, MOTION (friction at 20 degrees by
default), rows "line", no stress filter, `initial.equilibrate` = EQUILIBRATE, to 0.4 s."""
import sys
import tomllib
from pathlib import Path

import numpy as np
from mpi4py import MPI

from psph.app.run import run
from psph.config.load import apply_override, resolve, validate
from psph.io.snapshots import read_snapshots
from psph.verify.pressure import excess_pressure

BASE = Path(__file__).resolve().parents[2] / "tests" / "scenes" / "dipping_base.toml"


def variant_scene(v: str, motion: str, eq: float, sets: list[str]):
    """The dipping base with the VARIANT's line, MOTION and EQUILIBRATE (module docstring)."""
    data = tomllib.loads(BASE.read_text())
    line = [list(pt) for pt in eval(LINES[v])]
    data["name"] = f"dip_{v}"
    data["particles"]["layers"][0]["bottom"] = line
    poly = data["boundaries"]["polylines"][0]
    poly.update(points=line, motion=motion)
    poly.pop("rows")
    if motion != "friction":
        poly.pop("friction_angle")
    data.pop("stabilisation")
    data["initial"]["equilibrate"] = eq
    data["time"]["end"] = 0.4
    for a in sets:
        apply_override(data, a)
    return resolve(validate(data, str(BASE)))


LINES = {"dip": "[[-1.0, 2.0349], [41.0, 0.5676]]",  # 2 degrees
         "flat_dx": "[[-1.0, 2.0], [41.0, 2.0]]",     # lowest row 2.25: gap dx
         "flat_short": "[[-1.0, 2.24], [41.0, 2.24]]",  # gap 0.52 dx
         "flat_long": "[[-1.0, 2.26], [41.0, 2.26]]"}   # lowest row 2.75: gap 1.48 dx
v, out = sys.argv[1], sys.argv[2]
motion = sys.argv[3] if len(sys.argv) > 3 else "friction"
eq = sys.argv[4] if len(sys.argv) > 4 else "1.0"
sets = sys.argv[5:]
scene = variant_scene(v, motion, float(eq), sets)
run(scene, out, comm=MPI.COMM_SELF, quiet=True)
for s in read_snapshots(f"{out}/particles.h5"):
    ex = excess_pressure(s, scene) / 1e3
    z0 = s["x"][:, 1] - s["u"][:, 1]
    zl = np.interp(s["x"][:, 0] - s["u"][:, 0], *np.array(eval(LINES[v])).T)
    base = (z0 - zl) < 1.5 * 0.5
    print(f"{out} {v} {motion} t={s['time']:.2f} excess p kPa: all {ex.min():8.1f} "
          f"{ex.max():8.1f}  base rows {ex[base].min():8.1f} {ex[base].max():8.1f}"
          f"  |u|max {np.abs(s['u']).max():.2e}")

"""Thin layers on a fixed floor (collapse_3d's runaway layer): a dry
Drucker-Prager layer of n rows (phi = 30 degrees, c = 100 Pa, psi = 0), 4 m long, on a fixed floor
under gravity tilted by theta (an inclined floor), a slip wall upslope and a free toe.
Below theta = phi a layer should stay (the wall's shear stress bounded by c + sigma_n
tan(phi) holds it); the bench prints the mean downslope speed of the layer's middle
(x from 1 to 3 m) after 0.5 s for each thickness and tilt.

    python bench/studies/thin_layer_friction.py           # ~3 min, one rank
    python bench/studies/thin_layer_friction.py --probe   # the bottom row's stresses
        # against time at 15 degrees, 1 and 8 rows (~1 min)
    python bench/studies/thin_layer_friction.py --quick   # one row at 15 degrees to 0.05 s

Writes <out>/thin_layer_friction.json and .png.
"""

import argparse
import json
import math
import platform
import tempfile
import tomllib
from datetime import date
from pathlib import Path

import numpy as np
from floor_friction import DRY_SAND

from psph.app.run import run
from psph.config.load import resolve, validate
from psph.io.snapshots import read_snapshots

OUT = Path(__file__).resolve().parents[1] / "out"
DX = 0.05
SCENE = """
name = "thin_layer"
gravity = [{gx}, {gz}]
[domain]
min = [0.0, 0.0]
max = [8.0, 1.0]
[particles]
dx = {dx}
[[particles.blocks]]
min = [0.0, 0.0]
max = [4.0, {h}]
""" + DRY_SAND + """[boundaries]
left = {{ motion = "slip" }}
bottom = {{ motion = "fixed" }}
[initial]
k0 = 0.5
[pressure]
scheme = "none"
[time]
integrator = "symplectic"
cfl_solid = 0.3
end = {end}
[output]
interval = {end}
[stabilisation]
av_alpha = 1.0
"""


def probe() -> None:
    """The bottom row's shear and normal stress, its Drucker-Prager bound c + sigma_n
    tan(phi) on the shear, the shear the floor must carry (rho g sin(theta) h) and the
    layer's speed, at 15 degrees for 1 and 8 rows."""
    from mpi4py import MPI

    from psph.app.run import make_slabs
    from psph.solver.simulation import Simulation

    theta, g = 15.0, 9.81
    print("rows  t (s)  tau_xy  sigma_yy  bound  needed  v_x (m/s)")
    for rows in (1, 8):
        text = SCENE.format(gx=g * math.sin(math.radians(theta)),
                            gz=-g * math.cos(math.radians(theta)), dx=DX, h=rows * DX,
                            c=100.0, end=0.5)
        scene = resolve(validate(tomllib.loads(text)))
        sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
        for k in range(1500):
            sim.advance_one()
            if k in (0, 50, 400, 1499):
                st = sim.store
                n = st.n_owned
                x = st.x[:n]
                mid = (x[:, 0] > 1.0) & (x[:, 0] < 3.0)
                bottom = mid & (x[:, 1] < DX)
                s = st.stress[:n]
                bound = 100.0 - s[bottom, 1].mean() * math.tan(math.radians(30.0))
                needed = st.rho[0] * g * math.sin(math.radians(theta)) * rows * DX
                print(f"{rows:4d} {sim.t:6.3f} {s[bottom, 3].mean():7.1f} "
                      f"{s[bottom, 1].mean():9.1f} {bound:6.1f} {needed:7.1f} "
                      f"{st.v[:n][mid, 0].mean():9.4f}")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--probe", action="store_true",
                    help="the bottom row's stresses against time instead of the table")
    ap.add_argument("--quick", action="store_true",
                    help="one row at 15 degrees to 0.05 s (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of thin_layer_friction.json and .png (default bench/out)")
    args = ap.parse_args(argv)
    if args.probe:
        probe()
        return
    tilts, thicknesses, end = ((15.0,), (1,), 0.05) if args.quick else \
        ((0.0, 15.0, 25.0), (1, 2, 4, 8), 0.5)
    rows_out = []
    work = tempfile.TemporaryDirectory(prefix="psph-thin-")
    for theta in tilts:
        for rows in thicknesses:
            g = 9.81
            text = SCENE.format(gx=g * math.sin(math.radians(theta)),
                                gz=-g * math.cos(math.radians(theta)), dx=DX, h=rows * DX,
                                c=100.0, end=end)
            scene = resolve(validate(tomllib.loads(text)))
            out = Path(work.name) / f"t{theta:g}_r{rows}"
            run(scene, out, quiet=True)
            last = read_snapshots(out / "particles.h5")[-1]
            x0 = last["x"][:, 0] - last["u"][:, 0]
            middle = (x0 > 1.0) & (x0 < 3.0)  # away from the wall and the free toe
            u = float(np.mean(last["v"][middle, 0]))
            rows_out.append({"theta_deg": theta, "rows": rows, "mean_speed_m_s": u,
                             "max_speed_m_s": float(np.abs(last["v"][middle, 0]).max()),
                             "time_s": last["time"]})
            print(f"theta {theta:4.1f} deg, {rows} rows: mean downslope v {u:9.4f} m/s "
                  f"(at rest expected: theta < phi = 30)")
    work.cleanup()
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "thin_layer_friction.json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": platform.node(), "rows": rows_out},
        indent=1))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.4))
    for theta in sorted({r["theta_deg"] for r in rows_out}):
        sel = [r for r in rows_out if r["theta_deg"] == theta]
        ax.plot([r["rows"] for r in sel], [r["mean_speed_m_s"] for r in sel], "o-",
                label=f"tilt {theta:g} deg")
    ax.set(xscale="log", xlabel="rows in the layer", ylabel="mean downslope v at 0.5 s (m/s)",
           title="a layer on a fixed floor, phi = 30 deg, c = 100 Pa")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out / "thin_layer_friction.png", dpi=110)


if __name__ == "__main__":
    main()

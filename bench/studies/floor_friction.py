"""A block sliding on a friction surface: the floor's Coulomb friction against
g tan(phi_b) (docs/vv/collapse_3d.md, "the floor's friction").

A dry Drucker-Prager block (phi = 30 degrees, c = 2 kPa: it neither slumps nor shears, it
slides), 1.0 x 0.3 m between free-slip walls in y, `rows` particles thick at dx =
0.05 m, on `collapse_3d`'s floor (a surface of boundary particles, Coulomb at phi_b = 30
degrees, `weight_friction`), starts at 3 m/s after its gravity loading. A floor that
carries the Coulomb friction of the block's weight once decelerates it at
g tan(phi_b) = 5.66 m/s^2 whatever its thickness; the deceleration is the slope of its
mean velocity over 0.05-0.25 s.

The table: the block n = 2, 4, 8 rows thick with the floor's weight friction at full
strength (the rule as it is), at half strength and off, the deceleration over
g tan(phi_b); then the same in 2D on a friction polyline (whose wall limit reads the
Shepard-averaged stress above the line).

    python bench/studies/floor_friction.py            # the table, ~1.5 min on one rank
    python bench/studies/floor_friction.py --quick    # 2 rows in 3D at full strength

Prints the table, writes <out>/floor_friction.json. `block_deceleration` is the case
`tests/test_floor_friction.py` runs.
"""

import argparse
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
from mpi4py import MPI

from psph.app.run import make_slabs
from psph.config.load import load_scene
from psph.solver.simulation import Simulation

DX = 0.05
PHI_B = 30.0
C = 2.0e3  # the block's cohesion: it does not slump, and slides on the floor
# collapse_3d's dry sand (E, phi = 30 degrees, psi = 0) on the plane-strain cone, with a
# cohesion {c} (Pa), as a `str.format` template; thin_layer_friction.py shares it
DRY_SAND = """[material]
model = "drucker_prager"
E = 20.0e6
nu = 0.3
porosity = 0.4
rho_s = 2650.0
k = 1.0e-3
[material.plasticity]
phi = 30.0
c = {c}
c_r = {c}
eta = 0.0
psi = 0.0
"""
SCENE = """
name = "surface_floor_sliding"
gravity = [0.0, 0.0, -9.81]
[domain]
min = [-0.5, 0.0, 0.0]
max = [6.0, 0.3, 1.0]
[particles]
dx = {dx}
[[particles.blocks]]
min = [0.0, 0.0, 0.0]
max = [1.0, 0.3, {h}]
""" + DRY_SAND + """[boundaries]
front = {{ motion = "slip" }}
back = {{ motion = "slip" }}
[[boundaries.surfaces]]
vertices = [[-1.0, -0.5, 0.0], [7.0, -0.5, 0.0], [7.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]
triangles = [[0, 1, 2], [0, 2, 3]]
soil = "above"
motion = "friction"
friction_angle = {phi_b}
weight_friction = {wf}
[initial]
k0 = 0.5
equilibrate = 0.1
[pressure]
scheme = "none"
[time]
integrator = "symplectic"
cfl_solid = 0.3
end = 1.0
[stabilisation]
av_alpha = 1.0
"""


def scene_2d() -> str:
    """The same block in 2D on a friction polyline (the 2D boundary particles)."""
    s = SCENE.replace("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, -9.81]")
    s = s.replace("min = [-0.5, 0.0, 0.0]\nmax = [6.0, 0.3, 1.0]",
                  "min = [-0.5, 0.0]\nmax = [6.0, 1.0]")
    s = s.replace("min = [0.0, 0.0, 0.0]\nmax = [1.0, 0.3, {h}]",
                  "min = [0.0, 0.0]\nmax = [1.0, {h}]")
    s = s.replace('front = {{ motion = "slip" }}\nback = {{ motion = "slip" }}\n', "")
    return (s[:s.index("[[boundaries.surfaces]]")] + "[[boundaries.polylines]]\n"
            "points = [[-1.0, 0.0], [7.0, 0.0]]\n" + s[s.index('soil = "above"'):])


def block_deceleration(rows: int, weight_share: float = 1.0, dim: int = 3) -> float:
    """The block's deceleration (m/s^2) on one rank; `weight_share` scales the floor's
    weight friction (0: off; the table's other columns);
    dim = 2: on a friction polyline."""
    text = (SCENE if dim == 3 else scene_2d()).format(
        dx=DX, h=rows * DX, phi_b=PHI_B, c=C, wf="true" if weight_share > 0 else "false")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "surface_floor_sliding.toml"
        path.write_text(text)
        scene = load_scene(str(path))
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
    if weight_share > 0:
        sim.wall_particles.weight_friction *= weight_share
    sim.equilibrate()
    st = sim.store
    n = st.n_owned
    st.v[:n, 0] = 3.0
    mass = st.rho[:n] * st.vol[:n]
    times, speeds = [], []
    while sim.t < 0.25:
        sim.advance_one()
        if sim.failure is not None:
            raise RuntimeError(f"failed: {sim.failure}")
        if sim.t >= 0.05:
            times.append(sim.t)
            speeds.append(float(np.average(st.v[:n, 0], weights=mass)))
    return -float(np.polyfit(times, speeds, 1)[0])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="one case: 2 rows in 3D, the weight friction at full strength")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "out",
                    help="directory of floor_friction.json (default bench/out)")
    args = ap.parse_args(argv)
    g_tan = 9.81 * math.tan(math.radians(PHI_B))
    shares = (1.0,) if args.quick else (1.0, 0.5, 0.0)
    cases = [(3, 2)] if args.quick else [(d, r) for d in (3, 2) for r in (2, 4, 8)]
    print(f"deceleration / g tan(phi_b) (= {g_tan:.2f} m/s^2)")
    names = {1.0: "weight friction full", 0.5: "half", 0.0: "off"}
    print("| rows | " + " | ".join(names[s] for s in shares) + " |")
    print("|---|" + "---|" * len(shares))
    rows = []
    for dim, n in cases:
        cells = [block_deceleration(n, share, dim) / g_tan for share in shares]
        rows.append({"dim": dim, "rows": n, "weight_share": list(shares), "ratio": cells})
        print(f"| {n} ({dim}D) | " + " | ".join(f"{c:.3f}" for c in cells) + " |", flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "floor_friction.json").write_text(json.dumps(
        {"g_tan_phi_b": g_tan, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Basal sliding of a saturated block: how much shear traction a fixed base
transmits, and what pore pressure it makes, against the soil's own strength.

A block of saturated soil rests on the domain's bottom wall with hydrostatic p and the K0
effective stress (water table at its top), and is given a uniform horizontal velocity U at
t = 0. Nothing else acts along the base, so the block's mean deceleration times its mass
per metre of base is the basal shear traction (momentum balance of Eq. 26 over the block).
On a `fixed` base the bottom row shears plastically, and the traction must be the
Drucker-Prager strength of that row, tau_f = sqrt((kappa - xi I1)^2 - s_d^2) from
Eq. (14)-(16) at its current normal stresses (s_d^2: the J2 of the normal deviator), not a
numerical drag; on a `slip` base it must be zero. The basal row's excess pore pressure
p - p(t = 0) shows any spurious suction the wall makes.

`sliding_block` builds the scene (any overrides apply), runs it on one rank and returns
the time series (`tests/test_basal_sliding.py` runs it; `block_scene` is the scene other
tests use too). The basal strength it is compared with is
`psph.verify.sliding.basal_strength`.

    python bench/studies/sliding.py            # the table of the variants (~2 min)
    python bench/studies/sliding.py --quick    # the scene's settings alone, 30 steps

Prints the table, writes <out>/sliding.json (each variant's window means).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from mpi4py import MPI

from psph.app.run import make_slabs
from psph.config.load import load_scene
from psph.solver.simulation import Simulation
from psph.verify.sliding import basal_strength

BLOCK = """
name = "sliding_block"
description = "a saturated block sliding on the base (basal sliding)"
gravity = [0.0, -9.81]
[domain]
min = [0.0, 0.0]
max = [60.0, 8.0]
[particles]
dx = {dx}
[[particles.blocks]]
min = [2.0, 0.0]
max = [{x1}, {y1}]
[material]
model = "drucker_prager"
E = 12.5e6
nu = 0.33
porosity = 0.4
rho_s = 2650.0
k = 5.0e-8
K_l = 1.0e8
[material.plasticity]
phi = 10.0
c = 5.0e3
psi = 0.0
[boundaries]
left = {{ motion = "slip" }}
bottom = {{ motion = "fixed" }}
[initial]
water_table = "surface"
k0 = 0.5
[pressure]
scheme = "explicit"
[time]
integrator = "symplectic"
dt = 4.0e-4
allow_dt_above_solid_limit = true
end = 1.0
[stabilisation]
av_alpha = 1.0
"""

# the retrogressive slopes' clay softening (Section 4.5: c 55 -> 0.7 kPa, phi 10 -> 5 deg,
# eta = 5) as overrides of BLOCK: the block of nonlocal_sliding.py and its test
SLOPE_SOFTENING = ["material.plasticity.c=55.0e3", "material.plasticity.c_r=0.7e3",
                   "material.plasticity.phi_r=5.0", "material.plasticity.eta=5.0"]


def block_scene(overrides: list[str] | None = None, nx: int = 24, ny: int = 8,
                dx: float = 0.4):
    """The sliding-block scene: nx x ny particles of the Section 4.5 clay at spacing dx
    (no softening, c = 5 kPa, phi = 10 deg), on a fixed base, water table at its top."""
    text = BLOCK.format(dx=dx, x1=2.0 + nx * dx, y1=ny * dx)
    if any(o.replace(" ", "") == 'material.model="elastic"' for o in overrides or []):
        start = text.index("[material.plasticity]")
        text = text[:start] + text[text.index("[boundaries]"):]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sliding_block.toml"
        path.write_text(text)
        return load_scene(str(path), overrides or [])


def sliding_block(overrides: list[str] | None = None, velocity: float = 10.0,
                  steps: int = 300, every: int = 10, nx: int = 24, ny: int = 8,
                  dx: float = 0.4) -> dict:
    """Run the sliding block on one rank for `steps` steps from a uniform velocity
    `velocity` (m/s) and return, every `every` steps: time, mean velocity of the block,
    the basal traction from the momentum balance (Pa, positive against the motion, from
    the change of the mean velocity over the last `every` steps), the mean DP strength of
    the bottom row, and the mean, 5th percentile and minimum of its excess p
    (p - p at t = 0, Pa), with the minimum over the whole block; the bottom row's mean
    eps_p and softening variable eps_hat (eps_p with the local law)."""
    scene = block_scene(overrides, nx, ny, dx)
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
    sim.equilibrate()
    st = sim.store
    n = st.n_owned
    st.v[:n, 0] = velocity
    order = np.argsort(st.key[:n])
    base = (st.x[:n, 1] < dx)[order]
    p0 = st.p[:n][order].copy()
    mass = (st.rho[:n] * st.vol[:n]).sum()
    length = nx * dx
    rows = []
    v_last = velocity
    t_last = 0.0
    for k in range(1, steps + 1):
        sim.advance_one()
        if k % every:
            continue
        if sim.failure is not None:
            rows.append({"time": sim.t, "failed": sim.failure})
            break
        o = np.argsort(st.key[:n])
        vbar = float(np.average(st.v[:n, 0], weights=(st.rho[:n] * st.vol[:n])))
        traction = -(vbar - v_last) / (sim.t - t_last) * mass / length
        v_last, t_last = vbar, sim.t
        excess = st.p[:n][o] - p0
        hat = sim.softening.eps_hat[:n] if sim.softening else st.eps_p[:n]
        strength = basal_strength(st.stress[:n][o][base], hat[o][base], sim.dp)
        rows.append({"time": sim.t, "v_mean": vbar, "traction_Pa": traction,
                     "strength_Pa": float(strength.mean()),
                     "base_excess_mean_Pa": float(excess[base].mean()),
                     "base_excess_p05_Pa": float(np.percentile(excess[base], 5)),
                     "base_excess_min_Pa": float(excess[base].min()),
                     "excess_min_Pa": float(excess.min()),
                     "excess_max_Pa": float(excess.max()),
                     "base_eps_p": float(st.eps_p[:n][o][base].mean()),
                     "base_eps_hat": float(hat[o][base].mean())})
    return {"rows": rows, "mass_per_m": mass, "base_length_m": length,
            "velocity0": velocity}


VARIANTS = {
    "scene settings (alpha_Pi = 1, eps = 0.5)": [],
    "alpha_Pi = 0.1 (paper)": ["stabilisation.av_alpha=0.1"],
    "artificial stress off": ["stabilisation.artificial_stress=0.0"],
    "viscosity off": ["stabilisation.av_alpha=0.0", "stabilisation.av_beta=0.0"],
    "gravity-loaded first (initial.equilibrate = 1 s)": ["initial.equilibrate=1.0"],
    "slip base": ['boundaries.bottom.motion="slip"'],
    "elastic, slip base": ['material.model="elastic"', 'boundaries.bottom.motion="slip"'],
    "elastic, fixed base": ['material.model="elastic"'],
}


def summarise(result: dict, window: tuple[float, float] = (0.04, 0.12)) -> dict:
    """Mean over a time window of the traction, the strength and the basal excess p."""
    rows = [r for r in result["rows"] if "failed" not in r
            and window[0] <= r["time"] <= window[1] + 1e-9]
    if not rows:
        return {"failed": result["rows"][-1].get("failed")}
    pick = {k: float(np.mean([r[k] for r in rows])) for k in
            ("traction_Pa", "strength_Pa", "base_excess_mean_Pa", "base_excess_p05_Pa")}
    pick["excess_min_Pa"] = min(r["excess_min_Pa"] for r in rows)
    pick["v_end"] = rows[-1]["v_mean"]
    return pick


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--set", action="append", default=[], help="extra scene override")
    ap.add_argument("--quick", action="store_true",
                    help="the scene's settings alone, 30 steps (a smoke check)")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "out",
                    help="directory of sliding.json (default bench/out)")
    args = ap.parse_args(argv)
    variants = dict(list(VARIANTS.items())[:1]) if args.quick else VARIANTS
    steps, every, window = (30, 1, (0.004, 0.012)) if args.quick else (args.steps, 10,
                                                                       (0.04, 0.12))
    print(f"{'variant':44s} {'v(end)':>9s} {'traction':>9s} {'strength':>9s} "
          f"{'base dp':>9s} {'base p5':>9s} {'min dp':>9s}   (kPa, m/s)")
    table = {}
    for name, ov in variants.items():
        s = summarise(sliding_block(ov + args.set, steps=steps, every=every), window)
        table[name] = s
        if "failed" in s:
            print(f"{name:44s} failed: {s['failed']}")
            continue
        print(f"{name:44s} {s['v_end']:9.3f} {s['traction_Pa'] / 1e3:9.2f} "
              f"{s['strength_Pa'] / 1e3:9.2f} {s['base_excess_mean_Pa'] / 1e3:9.1f} "
              f"{s['base_excess_p05_Pa'] / 1e3:9.1f} {s['excess_min_Pa'] / 1e3:9.1f}")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "sliding.json").write_text(json.dumps(table, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The wall band of the non-local softening in a run (issue 17): a saturated block of the
Section 4.5 clay, with its softening (c 55 -> 0.7 kPa, phi 10 -> 5 deg, eta = 5; psi = 0),
slides at 10 m/s on a fixed base (`psph.verify.sliding`), at two spacings with the same
internal length l_c, the block the same size at both (9.6 m x 4.8 m). The base softens
only if the bottom row's eps_hat grows: this is the slope's basal band in a run of
seconds instead of an hour.

Per case, at the end (0.4 s, 1,000 steps of 4e-4 s): the block's mean velocity, the
basal traction from its momentum balance over the last 0.1 s, the bottom row's mean
eps_p and eps_hat (the softening variable the return mapping used), and the same for the
second row.

    .venv/bin/python bench/nonlocal_sliding.py            # the table
    .venv/bin/python bench/nonlocal_sliding.py --m 1      # m = 1 (plain average)

Writes bench/out/nonlocal_sliding.json.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).parent.parent
sys.path.insert(0, str(ROOT))
OUT = Path(__file__).parent / "out"

SOFTENING = ["material.plasticity.c=55.0e3", "material.plasticity.c_r=0.7e3",
             "material.plasticity.phi_r=5.0", "material.plasticity.eta=5.0"]
HEIGHT, LENGTH = 4.8, 9.6


def case(dx: float, length: float, m: float, steps: int = 1000, every: int = 250) -> dict:
    """One block: `length` = l_c (0: local law) at spacing dx."""
    from mpi4py import MPI

    from psph.run import make_slabs
    from psph.solver import Simulation
    from psph.verify.sliding import block_scene

    over = list(SOFTENING)
    if length > 0.0:
        over.append("material.plasticity.regularisation="
                    f"{{kind='nonlocal', length={length}, m={m}}}")
    nx, ny = round(LENGTH / dx), round(HEIGHT / dx)
    scene = block_scene(over, nx, ny, dx)
    sim = Simulation(scene, make_slabs(scene, MPI.COMM_SELF))
    sim.equilibrate()
    st = sim.store
    n = st.n_owned
    st.v[:n, 0] = 10.0
    mass = float((st.rho[:n] * st.vol[:n]).sum())
    rows = []
    v_last, t_last = 10.0, 0.0
    for k in range(1, steps + 1):
        sim.advance_one()
        if k % every:
            continue
        if sim.failure is not None:
            rows.append({"time": sim.t, "failed": str(sim.failure)})
            break
        vbar = float(np.average(st.v[:n, 0], weights=st.rho[:n] * st.vol[:n]))
        hat = sim.softening.eps_hat[:n] if sim.softening else st.eps_p[:n]
        y = st.x[:n, 1]
        bottom, second = y < dx, (y >= dx) & (y < 2 * dx)
        rows.append({"time": sim.t, "v_mean": vbar,
                     "traction_Pa": -(vbar - v_last) / (sim.t - t_last) * mass / (nx * dx),
                     "eps_p_bottom": float(st.eps_p[:n][bottom].mean()),
                     "eps_hat_bottom": float(hat[bottom].mean()),
                     "eps_p_second": float(st.eps_p[:n][second].mean()),
                     "eps_hat_second": float(hat[second].mean())})
        v_last, t_last = vbar, sim.t
    return {"dx": dx, "l_c": length, "m": m, "l_c_over_dx": length / dx, "rows": rows}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--m", type=float, default=2.0, help="the over-non-local weight")
    ap.add_argument("--length", type=float, default=1.2, help="l_c (m)")
    args = ap.parse_args(argv)
    out = []
    print(f"{'law':>22} {'dx':>6} {'l_c/dx':>6} {'t':>5} {'v':>6} {'traction':>9} "
          f"{'eps_p row1':>10} {'eps_hat row1':>12} {'eps_p row2':>10} {'eps_hat row2':>12}")
    for dx in (0.6, 0.4):
        for length in (0.0, args.length):
            c = case(dx, length, args.m)
            out.append(c)
            law = "local" if length == 0.0 else f"non-local m={args.m:g}"
            for r in c["rows"]:
                if "failed" in r:
                    print(f"{law:>22} {dx:6.3f} failed at {r['time']:.3f} s: {r['failed']}")
                    continue
                print(f"{law:>22} {dx:6.3f} {c['l_c_over_dx']:6.2f} {r['time']:5.2f} "
                      f"{r['v_mean']:6.2f} {r['traction_Pa'] / 1e3:7.1f}kPa "
                      f"{r['eps_p_bottom']:10.3f} {r['eps_hat_bottom']:12.3f} "
                      f"{r['eps_p_second']:10.3f} {r['eps_hat_second']:12.3f}")
    OUT.mkdir(exist_ok=True)
    tag = "" if args.m == 2.0 and args.length == 1.2 else f"-m{args.m:g}-lc{args.length:g}"
    (OUT / f"nonlocal_sliding{tag}.json").write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

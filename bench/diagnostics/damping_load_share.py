"""The load the global damping of Eq. (43)-(44) carries in Terzaghi's column (issue 37,
`terzaghi_3d` at 0.501 % of q at T_v = 0.1).

The damping force -rho c_d v acts on the soil's real settlement velocity, not only on the
loading's vibration. Quasi-statically, Eq. (45) then gives d sigma_zz / dz = rho c_d v_z:
at depth d the column carries q less rho c_d int_0^d v dz, and in the undrained lower part
that deficit is the pore pressure's. With c_d = eta_d sqrt(E / rho_s) / h (Eq. 44) it grows
as the particles get finer: it is an error of the damping, not of the discretisation.

The script runs the 2D `terzaghi` column (dx = 0.01 m, the projection at C_CFL^s = 0.4)
to T_v = 0.2 with the scene's eta_d = 0.02 and with eta_d = 0, and prints at T_v = 0.1
the error profile (p - p_a) / q against depth for both, and the share
rho c_d int_0^H v dz / q that Terzaghi's settlement rate predicts at the base.

    .venv/bin/python bench/diagnostics/damping_load_share.py       # ~30 s, one rank

Writes bench/out/damping_load_share.json.
"""

import csv
import json
import platform
import tempfile
from datetime import date
from pathlib import Path

import numpy as np

from psph.app.run import run
from psph.config.load import load_scene
from psph.io.snapshots import read_snapshots
from psph.physics.material import soil_from_scene
from psph.verify import terzaghi

OUT = Path(__file__).resolve().parents[1] / "out"
TV = 0.1
WINDOWS = ((0.01, 0.02), (0.02, 0.03), (0.03, 0.05), (0.05, 0.09))


def error_profile(out: Path, scene) -> tuple[np.ndarray, np.ndarray]:
    """Depths of the lattice rows and the row-mean (p - p_a) / q at the snapshot of T_v."""
    ref = terzaghi.from_scene(scene)
    snap = min(read_snapshots(out / "particles.h5"), key=lambda s: abs(ref.tv_of(s["time"]) - TV))
    depth = np.round(ref.height - (snap["x"][:, 1] - snap["u"][:, 1]), 6)
    err = (snap["p"] - ref.pressure(depth, snap["time"])) / ref.load
    rows = np.unique(depth)
    return rows, np.array([err[depth == r].mean() for r in rows])


def after_switch(out: Path, scene) -> list[dict]:
    """The base probe's p / p0 range and the largest kinetic energy in windows after the
    drained switch (history.csv)."""
    ref = terzaghi.from_scene(scene)
    rows = list(csv.DictReader(open(out / "history.csv")))
    t = np.array([float(r["time"]) for r in rows])
    p = np.array([float(r["p_base"]) for r in rows]) / ref.p0
    ke = np.array([float(r["kinetic_energy"]) for r in rows])
    out_rows = []
    for a, b in WINDOWS:
        m = (t >= a) & (t < b)
        out_rows.append({"window_s": [a, b], "p_base_over_p0": [float(p[m].min()),
                                                                float(p[m].max())],
                         "kinetic_energy_max_J": float(ke[m].max())})
    return out_rows


def predicted_share(scene) -> float:
    """rho c_d int_0^H v dz / q at T_v, v from Terzaghi's displacement (mixture density)."""
    ref = terzaghi.from_scene(scene)
    m = scene.material
    c_d = soil_from_scene(scene).damping_coefficient(0.02, scene.h)
    rho = (1.0 - m.porosity) * m.rho_s + m.porosity * m.rho_l
    depth = np.linspace(0.0, ref.height, 201)
    t, dt = ref.time_of(TV), 1e-5

    def column_displacement(time: float) -> float:
        return np.trapezoid([ref.displacement(d, time)[0] for d in depth], depth)

    rate = (column_displacement(t + dt) - column_displacement(t - dt)) / (2 * dt)
    return rho * c_d * rate / ref.load


def main() -> None:
    result = {"date": str(date.today()), "machine": platform.node(), "tv": TV, "runs": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for eta in (0.02, 0.0):
            scene = load_scene("terzaghi", ["verification.tv=[0.1, 0.2]",
                                            f"stabilisation.damping={eta}"])
            out = Path(tmp) / f"eta{eta}"
            summary = run(scene, out, quiet=True)
            depth, err = error_profile(out, scene)
            result["runs"][str(eta)] = {
                "max_abs_p_error_over_q": summary["errors"]["pressure"]["0.1"][
                    "max_abs_p_error_over_q"],
                "depth_m": depth.tolist(), "row_error_over_q": err.tolist(),
                "after_switch": after_switch(out, scene)}
    result["predicted_share_at_base"] = predicted_share(scene)
    a, b = (np.array(result["runs"][k]["row_error_over_q"]) for k in ("0.02", "0.0"))
    result["damping_part_at_base"] = float(a[-1] - b[-1])
    print(f"T_v = {TV}: (p - p_a) / q by depth, % (row means)")
    print(f"{'depth m':>8} {'eta_d 0.02':>11} {'eta_d 0':>9} {'difference':>11}")
    for i in list(range(0, len(depth), 10)) + [len(depth) - 1]:
        d = 100 * (a[i] - b[i])
        print(f"{depth[i]:8.3f} {100 * a[i]:+11.3f} {100 * b[i]:+9.3f} {d:+11.3f}")
    for k, r in result["runs"].items():
        print(f"eta_d = {k}: max |p - p_a| / q = {100 * r['max_abs_p_error_over_q']:.3f} %")
    print("after the drained switch: base p / p0 (min, max), largest kinetic energy (J)")
    for k, r in result["runs"].items():
        for w in r["after_switch"]:
            lo, hi = w["p_base_over_p0"]
            print(f"  eta_d = {k:4s} t = {w['window_s'][0]:.2f}-{w['window_s'][1]:.2f} s: "
                  f"{lo:.4f} .. {hi:.4f}, {w['kinetic_energy_max_J']:.3g}")
    print(f"damping's part at the base {100 * result['damping_part_at_base']:+.3f} % of q; "
          f"rho c_d int v dz / q = {100 * result['predicted_share_at_base']:.3f} %")
    OUT.mkdir(exist_ok=True)
    (OUT / "damping_load_share.json").write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()

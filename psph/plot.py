"""`psph plot OUT`: PNG pictures of a run (rank 0 only, serial reads).

Always: a scatter of the chosen field at the last snapshot. For a Terzaghi run: pore
pressure against depth at each verification T_v beside the analytical curves, and the
surface settlement against time beside the analytical settlement.
"""

import csv
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from psph.errors import SceneError  # noqa: E402
from psph.io.snapshots import read_snapshots  # noqa: E402
from psph.scene import validate  # noqa: E402
from psph.verify import terzaghi  # noqa: E402


def plot_run(out: Path, field: str = "p") -> list[Path]:
    out = Path(out)
    h5 = out / "particles.h5"
    if not h5.is_file():
        raise SceneError(f"plot {out}: no particles.h5 (is it a psph output directory?)")
    scene = validate(tomllib.loads((out / "scene.toml").read_text()), str(out / "scene.toml"))
    snaps = read_snapshots(h5)
    paths = [_field_picture(out, snaps[-1], field)]
    if scene.verification.reference == "terzaghi":
        paths.append(_terzaghi_picture(out, scene, snaps))
    return paths


def _field_picture(out: Path, snap: dict, field: str) -> Path:
    if field not in snap:
        raise SceneError(f"plot --field {field}: not a snapshot field "
                         f"({', '.join(k for k in snap if k not in ('time', 'step'))})")
    val = snap[field]
    if val.ndim > 1:
        val = np.linalg.norm(val, axis=1) if field != "stress" else val[:, 1]
    x = snap["x"]
    ext = np.ptp(x, axis=0) + 1e-12
    fig, ax = plt.subplots(figsize=(3 + 5 * ext[0] / ext.max(), 3 + 5 * ext[1] / ext.max()))
    sc = ax.scatter(x[:, 0], x[:, 1], c=val, s=4, cmap="viridis")
    fig.colorbar(sc, ax=ax, label=field)
    ax.set_aspect("equal")
    ax.set_title(f"{field} at t = {snap['time']:.4g} s")
    path = out / f"{field}.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _terzaghi_picture(out: Path, scene, snaps: list[dict]) -> Path:
    ref = terzaghi.from_scene(scene)
    top = max(b.max[1] for b in scene.particles.blocks)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.8))
    zz = np.linspace(0, ref.height, 200)
    colours = plt.cm.viridis(np.linspace(0, 0.9, max(len(scene.verification.tv), 1)))
    for tv, col in zip(scene.verification.tv, colours, strict=False):
        t = ref.time_of(tv)
        snap = min(snaps, key=lambda s, t=t: abs(s["time"] - t))
        depth = top - (snap["x"][:, 1] - snap["u"][:, 1])
        ax1.plot(snap["p"] / ref.load, depth, ".", ms=2.5, color=col)
        tv_act = float(ref.tv_of(snap["time"]))
        ax1.plot(ref.pressure(zz, snap["time"]) / ref.load, zz, "-", color=col, lw=1.2,
                 label=f"T_v = {tv_act:.3g}")
    ax1.invert_yaxis()
    ax1.set_xlabel("excess pore pressure p / q")
    ax1.set_ylabel("depth (m)")
    ax1.set_title("SPH (dots) vs analytical (lines)")
    ax1.legend(fontsize=8)
    rows = list(csv.DictReader((out / "history.csv").open()))
    t = np.array([float(r["time"]) for r in rows])
    s = np.array([float(r["settlement"]) for r in rows])
    ax2.plot(t, s * 1e3, ".", ms=2.5, label="SPH")
    ta = t[t >= ref.t_drain]
    ax2.plot(ta, ref.settlement(ta) * 1e3, "-", label="analytical")
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("surface settlement (mm)")
    ax2.set_title("surface settlement")
    ax2.legend()
    fig.suptitle(f"{scene.name}: Terzaghi consolidation (q = {ref.load:g} Pa)")
    path = out / "terzaghi.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path

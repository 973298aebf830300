"""`psph plot OUT`: PNG pictures of a run (rank 0 only, serial reads).

Always: a scatter of the chosen field at the last snapshot. For a Terzaghi run: pore
pressure against depth at each verification T_v beside the analytical curves, and the
surface settlement against time beside the analytical settlement.
"""

import csv
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402

from psph.analysis.views_3d import pictures_3d, plan_change_frames  # noqa: E402
from psph.config.boundaries import points_of  # noqa: E402
from psph.config.load import run_scene  # noqa: E402
from psph.config.rules import is_slope_3d  # noqa: E402
from psph.errors import SceneError  # noqa: E402
from psph.geometry.lattice import probe_ids  # noqa: E402
from psph.io.snapshots import read_snapshots  # noqa: E402
from psph.verify import history_errors, terzaghi  # noqa: E402
from psph.verify.harmonic import from_scene  # noqa: E402
from psph.verify.pressure import excess_pressure, phreatic_excess  # noqa: E402
from psph.verify.slope_3d import centre_section, centre_strip  # noqa: E402


def plot_run(out: Path, field: str = "p") -> list[Path]:
    out = Path(out)
    h5 = out / "particles.h5"
    if not h5.is_file():
        raise SceneError(f"plot {out}: no particles.h5 (is it a psph output directory?)")
    scene = run_scene(out)
    snaps = read_snapshots(h5)
    if field not in snaps[-1]:
        raise SceneError(f"plot --field {field}: not a snapshot field "
                         f"({', '.join(k for k in snaps[-1] if k not in ('time', 'step'))})")
    if scene.dim == 3:
        front = scene.boundaries.front.motion == "slip"
        paths = pictures_3d(out, snaps[-1], field, scene.particles.dx, scene.domain.min[2],
                            front)
    else:
        paths = [_field_picture(out, snaps[-1], field)]
    ref = scene.verification.reference
    if ref == "terzaghi":
        paths.append(_terzaghi_picture(out, scene, snaps))
    elif ref == "harmonic":
        paths.append(_harmonic_picture(out, scene, snaps))
    elif ref == "strip_footing":
        paths.append(_strip_picture(out, scene, snaps))
    elif ref == "collapse" and scene.dim == 2:  # 3D: the section, plan and perspective
        paths.append(_collapse_picture(out, scene, snaps))
    elif ref == "collapse" and is_slope_3d(scene):  # the centre line as the 2D scene's
        paths.append(_collapse_picture(out, scene, [centre_section(s, scene)
                                                    for s in snaps]))
        paths.append(plan_change_frames(out, snaps, scene.particles.dx,
                                        scene.domain.min[2], centre_strip(scene)[2]))
    elif ref == "cryer":
        paths.append(_cryer_picture(out, scene))
    return paths


def _cryer_picture(out: Path, scene) -> Path:
    """The centre probe's p / p0 against c t / a^2 beside Cryer's series (timed from the
    middle of the load's ramp, as `verify.cryer.centre_errors`)."""
    from psph.verify.cryer import from_scene as cryer_from_scene

    ref = cryer_from_scene(scene)
    hist = _history(out)
    t = hist["time"] - 0.5 * scene.loads[0].ramp
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(ref.time_factor(t), hist["p_centre"] / ref.p0, ".", ms=3, label="SPH, centre")
    ts = np.linspace(1e-4, max(float(t[-1]), 1e-3), 600)
    ax.plot(ref.time_factor(ts), ref.centre_pressure(ts) / ref.p0, "-", label="Cryer's series")
    ax.axhline(1.0, color="grey", lw=0.8, ls=":")
    ax.set(xlabel="c t / a^2", ylabel="p / p0 at the centre",
           title=f"{scene.name}: the Mandel-Cryer effect (p0 = {ref.p0:.0f} Pa)")
    ax.legend()
    path = out / "cryer.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def excess_of(snap: dict, scene) -> np.ndarray:
    """The excess pore pressure (Pa) the frames draw: over the current phreatic line
    (`phreatic_excess`) where the free surface is drained (`pressure.ponding =
    "drained"`, the collapses: water leaves through the face and the table falls with
    it; the paper on Fig. 16: above the phreatic line the negative pore pressure is
    "equal to excess pore-water pressure"), else over the surface's table
    (`excess_pressure`)."""
    if scene.pressure.ponding == "drained":
        return phreatic_excess(snap, scene)
    return excess_pressure(snap, scene)


def excess_label(scene) -> str:
    """The frames' name of `excess_of`."""
    return "excess p over the phreatic line" if scene.pressure.ponding == "drained" \
        else "excess p"


def _collapse_picture(out: Path, scene, snaps: list[dict]) -> Path:
    """Frames at up to 4 snapshot times: equivalent plastic strain, and for a coupled run
    the excess pore pressure (p minus the hydrostatic p of the water table, or behind a
    drained surface of the phreatic line, at the particle's current position,
    `excess_of`) and the mean
    effective stress (Figs. 14-17, 19-21, 24-25)."""
    if scene.output.times:  # the paper's frame times (Figs. 19-21), then the end
        picks = [min(range(len(snaps)), key=lambda i: abs(snaps[i]["time"] - t))
                 for t in scene.output.times] + [len(snaps) - 1]
    else:
        picks = np.linspace(0, len(snaps) - 1, 4).astype(int)
    frames = [snaps[i] for i in np.unique(picks)]
    coupled = scene.pressure.scheme != "none"
    cols = 3 if coupled else 1
    x_all = np.concatenate([f["x"] for f in frames])
    lo, hi = x_all.min(axis=0), x_all.max(axis=0)
    moved = np.concatenate([f["x"][f["eps_p"] > 1e-3, 0] for f in frames])
    if hi[1] - lo[1] < 0.25 * (hi[0] - lo[0]) and len(moved):
        lo[0] = max(lo[0], moved.min() - 0.2 * (hi[0] - moved.min()))  # a long slope: crop
    aspect = (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-9)
    wide = aspect < 0.25  # a slope: fields stacked in one column, frames one after another
    shape = (len(frames) * cols, 1) if wide else (len(frames), cols)
    width = 13.0 if wide else 5.5 * cols
    # a run-out many times the slope's height: exaggerate the vertical scale so that each
    # frame keeps a readable height (the title says by how much)
    stretch = max(1.0, 0.06 / aspect) if wide else 1.0
    fig, axes = plt.subplots(*shape, squeeze=False,
                             figsize=(width, 0.6 + shape[0] * (width * aspect * stretch * 1.25
                                                               + (0.3 if stretch > 1 else 0))))
    names = [m.name for m in scene.materials]
    lines = [points_of(line) for line in scene.boundaries.polylines]
    for r, f in enumerate(frames):
        fields = [("eps_p", np.log10(f["eps_p"] + 1e-4), "log10 eps_p", (-4, 1), "viridis")]
        if r == 0 and len(names) > 1 and "material" in f:  # the layers, before they move
            fields[0] = ("material", f["material"], "material " + ", ".join(
                f"{k} {n}" for k, n in enumerate(names)), (-0.5, len(names) - 0.5),
                         ListedColormap(plt.get_cmap("tab10").colors[:len(names)]))
        if coupled:
            mean = -(f["stress"][:, 0] + f["stress"][:, 1] + f["stress"][:, 2]) / 3e3
            # excess over the hydrostatic p of the water table at the current position,
            # as Figs. 14-17, 20 and 24 show (psph/verify/pressure.py); behind a drained
            # free surface the table is the current phreatic line (the paper on Fig. 16)
            ex = excess_of(f, scene) / 1e3
            # colour limits from the 99.5th percentile: a few extreme particles would
            # wash out the rest (the title gives the extremes); symmetric about 0
            lim = max(np.percentile(np.abs(ex), 99.5), 1e-6)
            top = max(np.percentile(mean, 99.5), 1e-6)
            fields += [("excess p", ex, f"{excess_label(scene)} (kPa; {ex.min():.0f} to "
                                        f"{ex.max():.0f})",
                        (-lim, lim), "RdBu_r"),
                       ("mean", mean, f"p' (kPa; max {mean.max():.0f})", (0, top), "magma")]
        for c, (_, val, label, (vmin, vmax), cmap) in enumerate(fields):
            ax = axes[r * cols + c, 0] if wide else axes[r, c]
            sc = ax.scatter(f["x"][:, 0], f["x"][:, 1], c=val, s=1.5, cmap=cmap, vmin=vmin,
                            vmax=vmax)
            for pts in lines:  # the rigid boundaries (bedrock)
                ax.plot(pts[:, 0], pts[:, 1], "k-", lw=0.8)
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
            ax.set_aspect(stretch)
            vex = f" (vertical scale x{stretch:.1f})" if stretch > 1 else ""
            ax.set_title(f"{label}, t = {f['time']:.3g} s{vex}", fontsize=9)
            fig.colorbar(sc, ax=ax, shrink=0.8)
    summary = out / "summary.json"
    if summary.is_file():
        m = json.loads(summary.read_text()).get("metrics", {}).get("collapse")
        if m:
            slides = f", {m['slides']} slides" if "slides" in m else ""
            fig.suptitle(f"{scene.name}: run-out {m['runout_m']:.2f} m, final height "
                         f"{m['final_height_m']:.2f} m, back scarp at {m['back_scarp_m']:.2f} m"
                         f"{slides}", fontsize=10)
    path = out / f"{scene.name}.png"
    # keep the suptitle clear of the first frame's title on a tall stack of frames
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 1.0 - 0.3 / fig.get_size_inches()[1]))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _history(out: Path) -> dict[str, np.ndarray]:
    rows = list(csv.DictReader((out / "history.csv").open()))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def _verification(out: Path, scene, hist) -> dict:
    """The probe comparison of psph.verify, also written to OUT/verification.json."""
    probes = {k: pos for k, (_, pos) in probe_ids(scene).items()}
    errors = history_errors(scene, hist, probes)
    (out / "verification.json").write_text(json.dumps(errors, indent=2) + "\n")
    return errors


def _harmonic_picture(out: Path, scene, snaps: list[dict]) -> Path:
    hist = _history(out)
    err = _verification(out, scene, hist)
    top = max(b.max[1] for b in scene.particles.blocks)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 5), width_ratios=[1.6, 1])
    t = hist["time"]
    names = list(err["probes"])
    colours = plt.cm.viridis(np.linspace(0, 0.85, len(names)))
    depths = [err["probes"][k]["depth_m"] for k in names]
    damped = from_scene(scene, True)
    tr, pr = damped.pressure_at(depths, float(t[-1]), 2.5e-4)
    _, pu = from_scene(scene, False).pressure_at(depths, float(t[-1]), 2.5e-4)
    for j, (name, col) in enumerate(zip(names, colours, strict=True)):
        ax1.plot(t, hist[f"p_{name}"] / 1e3, ".", ms=2.5, color=col)
        ax1.plot(tr, pr[:, j] / 1e3, "-", color=col, lw=1.2, label=f"z = {depths[j]:.2f} m")
        ax1.plot(tr, pu[:, j] / 1e3, ":", color=col, lw=1)
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel("excess pore pressure (kPa)")
    ax1.set_title("SPH (dots); 1D u-p_l reference with the same damping (lines), "
                  "undamped (dotted)", fontsize=9)
    ax1.legend(fontsize=8)
    tg, zc, _, ug = damped.solve(float(t[-1]), 2.5e-4)
    zn = np.linspace(0.0, damped.height, ug.shape[1])
    for t_show, col in ((0.135, "tab:blue"), (0.155, "tab:red")):
        snap = min(snaps, key=lambda s, t_show=t_show: abs(s["time"] - t_show))
        depth = top - (snap["x"][:, 1] - snap["u"][:, 1])
        ax2.plot(-snap["u"][:, 1] * 1e3, depth, ".", ms=2, color=col)
        k = int(np.argmin(np.abs(tg - snap["time"])))
        ax2.plot(ug[k] * 1e3, zn, "-", color=col, label=f"t = {snap['time']:.3f} s")
    ax2.invert_yaxis()
    ax2.set_xlabel("settlement (mm)")
    ax2.set_ylabel("depth (m)")
    ax2.set_title("settlement profile (paper Fig. 8)", fontsize=9)
    ax2.legend(fontsize=8)
    fig.suptitle(f"{scene.name}: 1D harmonic consolidation, load 3(1 - cos 75t) kPa")
    path = out / "harmonic.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _strip_picture(out: Path, scene, snaps: list[dict]) -> Path:
    hist = _history(out)
    err = _verification(out, scene, hist)
    t = hist["time"]
    fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(16, 4.8))
    for name, col in zip(err["probes"], ("tab:blue", "tab:red"), strict=False):
        e = err["probes"][name]
        ax1.plot(t, hist[f"p_{name}"] / 1e3, "-", color=col,
                 label=f"{name}: x = {e['x_m']:.2f} m, depth {e['depth_m']:.2f} m")
        ax1.plot([err["t_load_end_s"]], [e["undrained_reference_Pa"] / 1e3], "o", mfc="none",
                 color=col, ms=9)
        ax2.plot(t, -hist[f"uy_{name}"] * 1e3, "-", color=col, label=name)
    ax1.set_xscale("symlog", linthresh=0.1)
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel("excess pore pressure (kPa)")
    ax1.set_title("p at A and B (circles: undrained elastic q alpha / pi)", fontsize=9)
    ax1.legend(fontsize=8)
    ax2.set_xscale("symlog", linthresh=0.1)
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("settlement (mm)")
    ax2.set_title("settlement at A and B (paper Fig. 12a)", fontsize=9)
    ax2.legend(fontsize=8)
    snap = min(snaps, key=lambda s: abs(s["time"] - err["t_load_end_s"]))
    sc = ax3.scatter(snap["x"][:, 0], snap["x"][:, 1], c=snap["p"] / 1e3, s=2, cmap="viridis")
    fig.colorbar(sc, ax=ax3, label="p (kPa)")
    top = max(b.max[1] for b in scene.particles.blocks)
    ax3.set_xlim(0.0, 0.4 * top)
    ax3.set_ylim(0.6 * top, top)
    ax3.set_aspect("equal")
    ax3.set_title(f"p at t = {snap['time']:.3g} s (end of loading), top corner", fontsize=9)
    fig.suptitle(f"{scene.name}: flexible strip footing, q = {err['load_Pa'] / 1e3:g} kPa, "
                 f"half-width {err['load_half_width_m']:g} m (symmetry plane at x = 0)")
    path = out / "strip_footing.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


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
    vz = scene.dim - 1  # the vertical axis
    top = max(b.max[vz] for b in scene.particles.blocks)
    fig, (ax1, ax2, ax4) = plt.subplots(1, 3, figsize=(16, 4.8))
    zz = np.linspace(0, ref.height, 200)
    colours = plt.cm.viridis(np.linspace(0, 0.9, max(len(scene.verification.tv), 1)))
    for tv, col in zip(scene.verification.tv, colours, strict=False):
        t = ref.time_of(tv)
        snap = min(snaps, key=lambda s, t=t: abs(s["time"] - t))
        depth = top - (snap["x"][:, vz] - snap["u"][:, vz])
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
    ta = ta[np.linspace(0, len(ta) - 1, min(len(ta), 400)).astype(int)] if len(ta) else ta
    row = 0.5 * scene.particles.dx  # the loaded top row sits dx/2 below the surface
    s0 = float(ref.displacement(row, ref.t_drain)[0]) if scene.initial.undrained_load else 0.0
    ax2.plot(ta, (ref.displacement(row, ta) - s0) * 1e3, "-", label="analytical (row depth)")
    ax2.set_xlabel("time (s)")
    ax2.set_ylabel("settlement of the top row (mm)")
    ax2.set_title("settlement (top row, dx/2 deep)")
    ax2.legend()
    hist = _history(out)
    probes = [k[2:] for k in hist if k.startswith("p_") and k not in ("p_max", "p_min")]
    window = t <= 5 * ref.t_drain
    for name in probes:
        ax4.plot(t[window], hist[f"p_{name}"][window] / ref.load, ".-", ms=3, lw=0.8,
                 label=f"probe {name}")
    ax4.plot(t[window], hist["p_max"][window] / ref.load, "-", color="grey", lw=0.8,
             label="max over particles")
    ax4.axvline(ref.t_drain, color="k", ls=":", lw=1)
    ax4.axhline(ref.p0 / ref.load, color="k", ls="--", lw=0.8, label="undrained p0")
    ax4.set_xlabel("time (s)")
    ax4.set_ylabel("p / q")
    ax4.set_title("pressure history around the drained switch (dotted)", fontsize=9)
    ax4.legend(fontsize=8)
    fig.suptitle(f"{scene.name}: Terzaghi consolidation (q = {ref.load:g} Pa)")
    path = out / "terzaghi.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path

"""Analytical references and error norms used by tests, benchmarks and summaries: the
reference solutions of the built-in verification scenes and metrics over a run's
snapshots and histories. Nothing here runs a scene or reads a scene file."""

import numpy as np

from psph.verify import cryer, terzaghi
from psph.verify.harmonic import from_scene
from psph.verify.strip import loaded_half_width, undrained_pressure


def reference_times(scene) -> list[float]:
    """Physical times (s) of the scene's verification points."""
    if scene.verification.reference == "terzaghi":
        ref = terzaghi.from_scene(scene)
        return [ref.time_of(tv) for tv in scene.verification.tv]
    return []


def history_errors(scene, hist: dict[str, np.ndarray], probes: dict[str, tuple]) -> dict | None:
    """Probe histories (history.csv columns) against the scene's reference; None if the
    scene has no probe-based reference. `probes`: name -> initial (x, y) of the probe
    particle."""
    ref = scene.verification.reference
    if ref == "harmonic":
        return _harmonic(scene, hist, probes)
    if ref == "strip_footing":
        return _strip(scene, hist, probes)
    if ref == "cryer":
        return cryer.centre_errors(scene, hist["time"], hist["p_centre"])
    return None


def _harmonic(scene, hist, probes) -> dict:
    top = max(b.max[1] for b in scene.particles.blocks)
    names = list(probes)
    depths = [top - probes[k][1] for k in names]
    t = hist["time"]
    q2 = 2.0 * scene.loads[0].pressure  # peak load
    out = {"reference": "harmonic: 1D u-p_l grid solution (psph.verify.harmonic)",
           "load_peak_Pa": q2, "probes": {}}
    refs = {}
    for damped in (True, False):
        tr, pr = from_scene(scene, damped).pressure_at(depths, float(t[-1]), 2.5e-4)
        refs[damped] = np.stack([np.interp(t, tr, pr[:, j]) for j in range(len(names))], 1)
    for j, name in enumerate(names):
        p = hist[f"p_{name}"]
        rd, ru = refs[True][:, j], refs[False][:, j]
        out["probes"][name] = {
            "depth_m": depths[j],
            "max_abs_error_over_peak_load_same_damping": float(np.max(np.abs(p - rd)) / q2),
            "max_abs_error_over_peak_load_undamped": float(np.max(np.abs(p - ru)) / q2),
            "peak_Pa": float(p.max()), "peak_time_s": float(t[np.argmax(p)]),
            "reference_peak_Pa": float(rd.max()), "reference_peak_time_s":
                float(t[np.argmax(rd)]),
            "undamped_peak_Pa": float(ru.max()), "min_Pa": float(p.min()),
            "reference_min_Pa": float(rd.min()),
        }
    out["max_abs_error_over_peak_load"] = max(
        v["max_abs_error_over_peak_load_same_damping"] for v in out["probes"].values())
    return out


def _strip(scene, hist, probes) -> dict:
    top = max(b.max[1] for b in scene.particles.blocks)
    load = scene.loads[0]
    b = loaded_half_width(scene)
    t = hist["time"]
    k_load = int(np.argmin(np.abs(t - load.ramp)))
    out = {"reference": "undrained elastic strip load: p = q alpha / pi (psph.verify.strip)",
           "load_Pa": load.pressure, "load_half_width_m": b, "t_load_end_s": float(t[k_load]),
           "probes": {}}
    for name, (x, y) in probes.items():
        p = hist[f"p_{name}"]
        p_ref = float(undrained_pressure(load.pressure, b, x, top - y))
        out["probes"][name] = {
            "x_m": x, "depth_m": top - y,
            "p_at_load_end_Pa": float(p[k_load]), "undrained_reference_Pa": p_ref,
            "error_at_load_end_over_reference": float(abs(p[k_load] - p_ref) / p_ref),
            "peak_Pa": float(p.max()), "peak_time_s": float(t[np.argmax(p)]),
            "p_end_Pa": float(p[-1]), "settlement_end_m": float(-hist[f"uy_{name}"][-1]),
        }
    return out

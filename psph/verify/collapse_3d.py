"""Metrics of an axisymmetric granular collapse in 3D (scene `collapse_3d`)
against the experimental scaling of Lube, Huppert, Sparks and Hallworth (2004,
"Axisymmetric collapses of granular columns", J. Fluid Mech. 508): for a column of
radius r_i and height h_i, a = h_i / r_i, the run-out

    (r_inf - r_i) / r_i = 1.24 a          for a < 1.7,
                        = 1.6 a^(1/2)     for a > 1.7.

Lube et al.'s own fit of the final height could not be read here (only abstracts of the
paper are in reach), so the height is set beside the axisymmetric fit of Lajeunesse,
Monnier and Homsy (2005, "Granular slumping on a horizontal surface", Phys. Fluids 17,
a semicircular tube) as Kumar (2015, PhD thesis, Cambridge, Chapter 2) quotes it:
h_inf / r_i = a for a < 0.74 (the top undisturbed, as Lube et al. observe too), 0.74 above.
"""

import h5py
import numpy as np
from mpi4py import MPI

from psph.verify.distributed import percentiles, read_share


def lube_runout(a: float) -> float:
    """Lube et al.'s normalised run-out (r_inf - r_i) / r_i at aspect ratio a."""
    return 1.24 * a if a < 1.7 else 1.6 * a ** 0.5


def published_height(a: float) -> float:
    """The axisymmetric final height h_inf / r_i at aspect ratio a of Lajeunesse et al.
    (2005) as quoted in the module docstring."""
    return a if a < 0.74 else 0.74


def radial_metrics(x: np.ndarray, axis_xy, dx: float, comm=None) -> dict:
    """x: (N, 3) positions (this rank's share; collective over `comm`). The run-out
    radius: the 99.8th percentile of the distance from the column's axis (a few
    splashed particles do not count), its spread to the 99th; the final height: the
    top of the particles within 2 dx of the axis."""
    comm = MPI.COMM_SELF if comm is None else comm
    r = np.hypot(x[:, 0] - axis_xy[0], x[:, 1] - axis_xy[1])
    r99, r998 = percentiles(r, [99.0, 99.8], comm)
    near = r < 2.0 * dx
    top = comm.allreduce(float(x[near, 2].max()) if near.any() else -np.inf, op=MPI.MAX)
    return {"runout_radius_m": r998, "runout_spread_m": r998 - r99,
            "final_height_m": top + 0.5 * dx}


def axisymmetric_verification(path, scene, comm) -> dict:
    """The `collapse` block of a `collapse_3d` run from its snapshots (collective): the
    radial metrics of every snapshot, and of the last against Lube et al.'s law."""
    cyl = scene.particles.cylinders[0]
    dx = scene.particles.dx
    ri, hi = cyl.radius, cyl.height
    a = hi / ri
    series = []
    with h5py.File(path, "r") as f:
        for name in sorted(f["snapshots"]):
            g = f["snapshots"][name]
            snap = read_share(g, ("x",), comm)
            m = radial_metrics(snap["x"], cyl.base[:2], dx, comm)
            m["time_s"] = float(g.attrs["time"])
            series.append(m)
    last = series[-1]
    runout = (last["runout_radius_m"] - ri) / ri
    law = lube_runout(a)
    return {"collapse_3d": {
        "reference": "Lube et al. (2004), axisymmetric collapses: (r_inf - r_i) / r_i = "
                     "1.24 a (a < 1.7), 1.6 a^(1/2) (a > 1.7)",
        "aspect_ratio": a, "initial_radius_m": ri, "initial_height_m": hi,
        "runout_normalised": runout, "lube_runout_normalised": law,
        "runout_error": runout / law - 1.0,
        "final_height_m": last["final_height_m"],
        "final_height_over_initial_radius": last["final_height_m"] / ri,
        "height_reference": "Lajeunesse et al. (2005), axisymmetric, as quoted by Kumar "
                            "(2015): h_inf / r_i = a (a < 0.74), 0.74 (a > 0.74)",
        "published_height_over_initial_radius": published_height(a),
        "time_s": last["time_s"],
        "series": {k: [m[k] for m in series] for k in series[0]}}}

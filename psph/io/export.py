"""`psph export OUT --format vtu|xdmf`: snapshots for ParaView and other VTK tools.

vtu: one `OUT/vtu/particles_<step>.vtu` per snapshot written with meshio (vertex cells,
point data p, n, eps_p, id, u, v, stress), and `OUT/particles.pvd`, the time series that
ParaView opens. xdmf: rewrites `OUT/particles.xdmf`, the sidecar over `particles.h5`
itself (no copy of the data); meshio's XDMF time series keeps the mesh fixed, which moving
particles are not.
"""

from pathlib import Path

import numpy as np

from psph.errors import SceneError
from psph.io.snapshots import read_snapshots, write_xdmf


def export_run(out: Path, fmt: str) -> list[Path]:
    """Write the export files of output directory `out`; returns their paths."""
    out = Path(out)
    h5 = out / "particles.h5"
    if not h5.is_file():
        raise SceneError(f"export {out}: no particles.h5 (is it a psph output directory?)")
    snaps = read_snapshots(h5)
    if fmt == "xdmf":
        entries = [(f"{s['step']:08d}", s["time"], len(s["id"])) for s in snaps]
        dim = snaps[0]["x"].shape[1] if snaps else 2
        path = out / "particles.xdmf"
        write_xdmf(path, "particles.h5", entries, dim)
        return [path]
    import meshio

    vtu_dir = out / "vtu"
    vtu_dir.mkdir(exist_ok=True)
    written = []
    for s in snaps:
        n, dim = s["x"].shape
        points = np.zeros((n, 3))
        points[:, :dim] = s["x"]
        data = {"id": s["id"], "p": s["p"], "n": s["n"], "eps_p": s["eps_p"],
                "material": s.get("material", np.zeros(n, np.int64)),
                "plastic_work": s.get("plastic_work", np.zeros(n)),
                "u": _pad3(s["u"]), "v": _pad3(s["v"]), "stress": s["stress"]}
        mesh = meshio.Mesh(points, [("vertex", np.arange(n).reshape(-1, 1))],
                           point_data=data)
        path = vtu_dir / f"particles_{s['step']:08d}.vtu"
        meshio.write(path, mesh, file_format="vtu")
        written.append((s["time"], path))
    pvd = out / "particles.pvd"
    rows = "\n".join(f'    <DataSet timestep="{t:.9g}" file="vtu/{p.name}"/>'
                     for t, p in written)
    pvd.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                   f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")
    return [p for _, p in written] + [pvd]


def _pad3(a: np.ndarray) -> np.ndarray:
    out = np.zeros((len(a), 3))
    out[:, :a.shape[1]] = a
    return out

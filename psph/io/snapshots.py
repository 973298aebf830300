"""Collective HDF5 snapshots (h5py mpio driver), `/snapshots/<step>` with one dataset a
field (docs/guide/outputs.md), and the XDMF sidecar that opens them in ParaView."""

from pathlib import Path

import h5py
import numpy as np

import psph
from psph.errors import SceneError

# Output field -> (unit, description); shapes (n,), or (n, dim) for vectors and (n, 6) for
# the stress.
SNAPSHOT_FIELDS = {
    "id": ("1", "stable global particle id"),
    "x": ("m", "position"),
    "u": ("m", "displacement from the initial position"),
    "v": ("m/s", "velocity"),
    "p": ("Pa", "pore-water pressure, compression positive"),
    "n": ("1", "porosity"),
    "stress": ("Pa", "effective stress xx, yy, zz, xy, yz, zx, tension positive"),
    "eps_p": ("1", "equivalent plastic strain"),
    "plastic_work": ("J/m^3", "dissipated plastic work sigma' : d eps_p, accumulated"),
    "vol": ("m^2", "particle volume: per unit thickness in 2D (sum plastic_work vol: J/m), "
            "m^3 in 3D"),
    "material": ("1", "index of the particle's material (0: [material] or the first of "
                 "[[materials]], in scene order)"),
}


def snapshot_arrays(store) -> dict[str, np.ndarray]:
    """The owned particles' output fields (copies, in output layout)."""
    n = store.n_owned
    stress6 = np.zeros((n, 6))  # 2D: xx, yy, zz, xy with yz = zx = 0
    stress6[:, :store.stress.shape[1]] = store.stress[:n]
    return {
        "id": store.key[:n].astype(np.int64),
        "x": store.x[:n].copy(),
        "u": store.u[:n].copy(),
        "v": store.v[:n].copy(),
        "p": store.p[:n].copy(),
        "n": store.poro[:n].copy(),
        "stress": stress6,
        "eps_p": store.eps_p[:n].copy(),
        "plastic_work": store.plastic_work[:n].copy(),
        "vol": store.vol[:n].copy(),
        "material": store.material[:n].astype(np.int64),
    }


def write_rows(dset, start: int, a: np.ndarray) -> None:
    """Collective write of rows start..start+len(a) of `dset` from every rank. A rank with
    no rows still takes part (h5py's slicing would skip the call and hang the others)."""
    fspace = dset.id.get_space()
    if len(a):
        count = a.shape
        fspace.select_hyperslab((start,) + (0,) * (a.ndim - 1), count)
        mspace = h5py.h5s.create_simple(count)
        buf = np.ascontiguousarray(a)
    else:
        fspace.select_none()
        mspace = h5py.h5s.create_simple((1,) + a.shape[1:])
        mspace.select_none()
        buf = np.zeros((1,) + a.shape[1:], a.dtype)
    dset.id.write(mspace, fspace, buf, dxpl=_collective_transfer())


def _collective_transfer():
    """A dataset-transfer property list for collective MPI-IO (h5py's low-level API)."""
    dxpl = h5py.h5p.create(h5py.h5p.DATASET_XFER)
    dxpl.set_dxpl_mpio(h5py.h5fd.MPIO_COLLECTIVE)
    return dxpl


class SnapshotWriter:
    """`OUT/particles.h5`, opened collectively once; `write` is collective.

    With `resume_step` (a restart) an existing file is reopened: snapshots written after
    that step by the interrupted run are dropped, the earlier ones are kept.
    """

    def __init__(self, path: Path, comm, dim: int, scene_toml: str,
                 resume_step: int | None = None):
        self.path = Path(path)
        self.comm = comm
        self.entries: list[tuple[str, float, int]] = []
        if resume_step is not None and self.path.is_file():
            self.f = h5py.File(self.path, "a", driver="mpio", comm=comm)
            snaps = self.f.require_group("snapshots")
            for name in sorted(snaps):
                g = snaps[name]
                if int(g.attrs["step"]) > resume_step:
                    del snaps[name]
                else:
                    self.entries.append((name, float(g.attrs["time"]), len(g["id"])))
            return
        self.f = h5py.File(self.path, "w", driver="mpio", comm=comm)
        self.f.attrs["dim"] = dim
        self.f.attrs["scene"] = scene_toml
        self.f.attrs["psph_version"] = psph.__version__
        self.f.create_group("snapshots")

    def write(self, step: int, t: float, store) -> None:
        arrays = snapshot_arrays(store)
        n_local = store.n_owned
        counts = self.comm.allgather(n_local)
        start = sum(counts[: self.comm.Get_rank()])
        total = sum(counts)
        name = f"{step:08d}"
        if name in self.f["snapshots"]:  # a restart at this very step rewrites it
            del self.f["snapshots"][name]
            self.entries = [e for e in self.entries if e[0] != name]
        g = self.f["snapshots"].create_group(name)
        g.attrs["time"] = t
        g.attrs["step"] = step
        for key, a in arrays.items():
            shape = (total,) + a.shape[1:]
            d = g.create_dataset(key, shape=shape, dtype=a.dtype)
            d.attrs["unit"], d.attrs["description"] = SNAPSHOT_FIELDS[key]
            write_rows(d, start, a)
        self.f.flush()
        self.entries.append((name, t, total))

    def close(self) -> None:
        self.f.close()


def write_xdmf(path: Path, h5name: str, entries, dim: int) -> None:
    """An XDMF 3 temporal collection of polyvertex grids, one per snapshot."""
    geo = "XY" if dim == 2 else "XYZ"
    grids = []
    for name, t, n in entries:
        base = f"{h5name}:/snapshots/{name}"

        def item(field, comps, n=n, base=base, kind="Float"):
            dims = f"{n}" if comps == 1 else f"{n} {comps}"
            return (f'<DataItem Dimensions="{dims}" NumberType="{kind}" Precision="8" '
                    f'Format="HDF">{base}/{field}</DataItem>')

        attrs = "".join(
            f'<Attribute Name="{f}" AttributeType="{"Scalar" if c == 1 else "Vector"}" '
            f'Center="Node">{item(f, c)}</Attribute>'
            for f, c in (("p", 1), ("n", 1), ("eps_p", 1), ("u", dim), ("v", dim)))
        attrs += (f'<Attribute Name="stress" AttributeType="Tensor6" Center="Node">'
                  f'{item("stress", 6)}</Attribute>')
        attrs += (f'<Attribute Name="material" AttributeType="Scalar" Center="Node">'
                  f'{item("material", 1, kind="Int")}</Attribute>')
        grids.append(
            f'<Grid Name="{name}" GridType="Uniform"><Time Value="{t:.9g}"/>'
            f'<Topology TopologyType="Polyvertex" NumberOfElements="{n}"/>'
            f'<Geometry GeometryType="{geo}">{item("x", dim)}</Geometry>{attrs}</Grid>')
    text = ('<?xml version="1.0" ?>\n<Xdmf Version="3.0"><Domain>'
            '<Grid Name="particles" GridType="Collection" CollectionType="Temporal">\n'
            + "\n".join(grids) + "\n</Grid></Domain></Xdmf>\n")
    Path(path).write_text(text)


def read_snapshots(path: Path) -> list[dict]:
    """All snapshots of a particles.h5 as dicts of arrays sorted by id (serial read).
    A missing, truncated or foreign file raises SceneError (exit 2) with one line."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(f"{path}: no such file")
    out = []
    try:
        with h5py.File(path, "r") as f:
            if "snapshots" not in f:
                raise SceneError(f"{path}: not a psph particles.h5 (no /snapshots group)")
            for name in sorted(f["snapshots"]):
                g = f["snapshots"][name]
                ids = g["id"][()]
                order = np.argsort(ids)
                snap = {k: g[k][()][order] for k in g}
                snap["time"] = float(g.attrs["time"])
                snap["step"] = int(g.attrs["step"])
                out.append(snap)
    except SceneError:
        raise
    except (OSError, KeyError, ValueError, IndexError) as e:
        reason = (str(e).strip().splitlines() or [type(e).__name__])[0][:160]
        raise SceneError(f"{path}: unreadable or truncated particles.h5 ({reason})") from None
    return out

"""Collective HDF5 snapshots (h5py mpio driver) in the schema of DESIGN.md, and the XDMF
sidecar that opens them in ParaView."""

from pathlib import Path

import h5py
import numpy as np

import psph

# Output field -> (unit, description); shapes follow DESIGN.md.
SNAPSHOT_FIELDS = {
    "id": ("1", "stable global particle id"),
    "x": ("m", "position"),
    "u": ("m", "displacement from the initial position"),
    "v": ("m/s", "velocity"),
    "p": ("Pa", "pore-water pressure, compression positive"),
    "n": ("1", "porosity"),
    "stress": ("Pa", "effective stress xx, yy, zz, xy, yz, zx, tension positive"),
    "eps_p": ("1", "equivalent plastic strain"),
}


def snapshot_arrays(store) -> dict[str, np.ndarray]:
    """The owned particles' output fields (copies, in output layout)."""
    n = store.n_owned
    stress6 = np.zeros((n, 6))
    stress6[:, :4] = store.stress[:n]
    return {
        "id": store.key[:n].astype(np.int64),
        "x": store.x[:n].copy(),
        "u": store.u[:n].copy(),
        "v": store.v[:n].copy(),
        "p": store.p[:n].copy(),
        "n": store.poro[:n].copy(),
        "stress": stress6,
        "eps_p": store.eps_p[:n].copy(),
    }


class SnapshotWriter:
    """`OUT/particles.h5`, opened collectively once; `write` is collective."""

    def __init__(self, path: Path, comm, dim: int, scene_toml: str):
        self.path = Path(path)
        self.comm = comm
        self.f = h5py.File(self.path, "w", driver="mpio", comm=comm)
        self.f.attrs["dim"] = dim
        self.f.attrs["scene"] = scene_toml
        self.f.attrs["psph_version"] = psph.__version__
        self.f.create_group("snapshots")
        self.entries: list[tuple[str, float, int]] = []

    def write(self, step: int, t: float, store) -> None:
        arrays = snapshot_arrays(store)
        n_local = store.n_owned
        counts = self.comm.allgather(n_local)
        start = sum(counts[: self.comm.Get_rank()])
        total = sum(counts)
        name = f"{step:08d}"
        g = self.f["snapshots"].create_group(name)
        g.attrs["time"] = t
        g.attrs["step"] = step
        for key, a in arrays.items():
            shape = (total,) + a.shape[1:]
            d = g.create_dataset(key, shape=shape, dtype=a.dtype)
            d.attrs["unit"], d.attrs["description"] = SNAPSHOT_FIELDS[key]
            with d.collective:
                d[start:start + n_local] = a
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

        def item(field, comps, n=n, base=base):
            dims = f"{n}" if comps == 1 else f"{n} {comps}"
            return (f'<DataItem Dimensions="{dims}" NumberType="Float" Precision="8" '
                    f'Format="HDF">{base}/{field}</DataItem>')

        attrs = "".join(
            f'<Attribute Name="{f}" AttributeType="{"Scalar" if c == 1 else "Vector"}" '
            f'Center="Node">{item(f, c)}</Attribute>'
            for f, c in (("p", 1), ("n", 1), ("eps_p", 1), ("u", dim), ("v", dim)))
        attrs += (f'<Attribute Name="stress" AttributeType="Tensor6" Center="Node">'
                  f'{item("stress", 6)}</Attribute>')
        grids.append(
            f'<Grid Name="{name}" GridType="Uniform"><Time Value="{t:.9g}"/>'
            f'<Topology TopologyType="Polyvertex" NumberOfElements="{n}"/>'
            f'<Geometry GeometryType="{geo}">{item("x", dim)}</Geometry>{attrs}</Grid>')
    text = ('<?xml version="1.0" ?>\n<Xdmf Version="3.0"><Domain>'
            '<Grid Name="particles" GridType="Collection" CollectionType="Temporal">\n'
            + "\n".join(grids) + "\n</Grid></Domain></Xdmf>\n")
    Path(path).write_text(text)


def read_snapshots(path: Path) -> list[dict]:
    """All snapshots of a particles.h5 as dicts of arrays sorted by id (serial read)."""
    out = []
    with h5py.File(path, "r") as f:
        for name in sorted(f["snapshots"]):
            g = f["snapshots"][name]
            ids = g["id"][()]
            order = np.argsort(ids)
            snap = {k: g[k][()][order] for k in g}
            snap["time"] = float(g.attrs["time"])
            snap["step"] = int(g.attrs["step"])
            out.append(snap)
    return out

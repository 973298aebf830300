"""Checkpoint/restart: `OUT/checkpoint.h5` holds every particle field and the run's clock
and schedules, so a restarted run continues bitwise (on any rank count: the neighbour
order does not depend on the partition).

Written collectively (h5py mpio driver, each rank its owned rows at its offset) into
`checkpoint.h5.tmp`, then renamed over `checkpoint.h5`: until the rename the previous
checkpoint stays valid, and a file without the `complete` mark is never accepted.
"""

import json
import os
from pathlib import Path

import h5py
import numpy as np

import psph
from psph.errors import SceneError
from psph.io.snapshots import write_rows
from psph.particles import ADDED_FIELDS, FIELDS

FORMAT = "psph-checkpoint-1"


def write_checkpoint(path: Path, comm, store, meta: dict, history: list[dict] | None = None,
                     alive: np.ndarray | None = None) -> None:
    """Collective: all particle fields of the owned rows, `meta` (JSON-able, the same on
    every rank), rank 0's diagnostics rows `history` (given on rank 0) and the `alive`
    mask of the ids still in the run (the same on every rank)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    n_local = store.n_owned
    counts = comm.allgather(n_local)
    start = sum(counts[: comm.Get_rank()])
    total = sum(counts)
    with h5py.File(tmp, "w", driver="mpio", comm=comm) as f:
        f.attrs["format"] = FORMAT
        f.attrs["psph_version"] = psph.__version__
        f.attrs["meta"] = json.dumps(meta)
        g = f.create_group("particles")
        for fld in FIELDS:
            a = store.arrays[fld.name]
            d = g.create_dataset(fld.name, shape=(total,) + a.shape[1:], dtype=a.dtype)
            write_rows(d, start, a[:n_local])
        text = np.frombuffer(json.dumps(history or []).encode(), np.uint8) \
            if comm.Get_rank() == 0 else None
        size = comm.bcast(len(text) if text is not None else 0, root=0)
        d = f.create_dataset("history_json", shape=(size,), dtype=np.uint8)
        if text is not None and size:
            d[:] = text  # independent write from rank 0
        if alive is not None:
            d = f.create_dataset("alive", shape=alive.shape, dtype=np.uint8)
            if comm.Get_rank() == 0 and len(alive):
                d[:] = alive.astype(np.uint8)
        f.attrs["complete"] = 1  # the last write: a file without it was cut short
    comm.Barrier()
    if comm.Get_rank() == 0:
        os.replace(tmp, path)  # atomic on POSIX: readers see the old or the new file
    comm.Barrier()


def read_checkpoint(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    """(meta, global arrays of every particle field). Raises SceneError (exit 2) with one
    line if the file is missing, truncated, incomplete or not a psph checkpoint."""
    path = Path(path)
    where = f"--restart {path}"
    if not path.is_file():
        raise SceneError(f"{where}: no such checkpoint file")
    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT:
                raise SceneError(f"{where}: not a psph checkpoint (format attribute "
                                 f"{f.attrs.get('format')!r}, expected {FORMAT!r})")
            if f.attrs.get("complete") != 1:
                raise SceneError(f"{where}: incomplete checkpoint (the writer was "
                                 "interrupted); use the previous one")
            meta = json.loads(f.attrs["meta"])
            arrays = {fld.name: f["particles"][fld.name][()] for fld in FIELDS
                      if fld.name not in ADDED_FIELDS or fld.name in f["particles"]}
            n_ids = meta.get("n_ids", meta.get("n_global"))
            alive = f["alive"][()].astype(bool) if "alive" in f else np.ones(n_ids, bool)
    except SceneError:
        raise
    except (OSError, KeyError, ValueError) as e:
        raise SceneError(f"{where}: unreadable checkpoint ({_reason(e)})") from None
    n = meta.get("n_global")
    for name in ADDED_FIELDS:
        arrays.setdefault(name, np.zeros(n))
    bad = [k for k, a in arrays.items() if len(a) != n]
    if bad:
        raise SceneError(f"{where}: corrupt checkpoint (field {bad[0]} has "
                         f"{len(arrays[bad[0]])} rows, expected {n})")
    if int(alive.sum()) != n:
        raise SceneError(f"{where}: corrupt checkpoint ({int(alive.sum())} ids alive, "
                         f"{n} particles)")
    arrays["alive"] = alive
    meta.setdefault("removals_done", 0)
    return meta, arrays


def _reason(e: Exception) -> str:
    text = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
    return text[:160]


def read_history(path: Path) -> list[dict]:
    """The diagnostics rows saved with a checkpoint (read_checkpoint has validated it)."""
    with h5py.File(path, "r") as f:
        return json.loads(f["history_json"][()].tobytes().decode() or "[]")

"""Checkpoint/restart: `OUT/checkpoint.h5` holds every particle field and the run's clock
and schedules, so a restarted run continues bitwise (on any rank count: the neighbour
order does not depend on the partition).

Written collectively (h5py mpio driver, each rank its owned rows at its offset) into
`checkpoint.h5.tmp`, then renamed over `checkpoint.h5`: until the rename the previous
checkpoint stays valid, and a file without the `complete` mark is never accepted.

A restart (`read_restart`) reads on each rank only a share of the rows, a chunk at a
time: the slab cuts come from the shares' coordinates (the same bits as `slab_cuts` of
all of them), and each row goes to the rank owning it. No rank holds an array of all
particles or of all ids.

Removed particles (format `psph-checkpoint-1`): the ids removed by `remove` regions are
stored as `removed_ids` (int64, in no particular order; meta `n_removed`), not as a mask
one entry per id, which would be as long as all ids. A checkpoint holding the `alive`
mask (uint8, one per id) instead also restarts; a reader that knows only `alive` restarts
a checkpoint with `removed_ids` only if nothing was removed (it reads a missing `alive`
as all alive).
"""

import json
import os
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np

import psph
from psph.errors import SceneError
from psph.io.snapshots import write_rows
from psph.state.particles import ADDED_FIELDS, FIELDS, fields_of_dim

FORMAT = "psph-checkpoint-1"


CHUNK_ROWS = 1 << 20  # rows of one column read at a time on a restart
EXCHANGE_BYTES = 1 << 23  # a restart's chunk of whole rows, read and sent at a time


def write_checkpoint(path: Path, comm, store, meta: dict, history: list[dict] | None = None,
                     removed: np.ndarray | None = None) -> None:
    """Collective: all particle fields of the owned rows, `meta` (JSON-able, the same on
    every rank), rank 0's diagnostics rows `history` (given on rank 0) and this rank's
    share `removed` of the ids removed from the run."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    n_local = store.n_owned
    removed = np.zeros(0, np.int64) if removed is None else np.asarray(removed, np.int64)
    counts = comm.allgather((n_local, len(removed)))
    start = sum(c[0] for c in counts[: comm.Get_rank()])
    total = sum(c[0] for c in counts)
    r_start = sum(c[1] for c in counts[: comm.Get_rank()])
    r_total = sum(c[1] for c in counts)
    with h5py.File(tmp, "w", driver="mpio", comm=comm) as f:
        f.attrs["format"] = FORMAT
        f.attrs["psph_version"] = psph.__version__
        f.attrs["meta"] = json.dumps(dict(meta, n_removed=r_total))
        g = f.create_group("particles")
        for fld in store.fields:
            a = store.arrays[fld.name]
            d = g.create_dataset(fld.name, shape=(total,) + a.shape[1:], dtype=a.dtype)
            write_rows(d, start, a[:n_local])
        text = np.frombuffer(json.dumps(history or []).encode(), np.uint8) \
            if comm.Get_rank() == 0 else None
        size = comm.bcast(len(text) if text is not None else 0, root=0)
        d = f.create_dataset("history_json", shape=(size,), dtype=np.uint8)
        if text is not None and size:
            d[:] = text  # independent write from rank 0
        d = f.create_dataset("removed_ids", shape=(r_total,), dtype=np.int64)
        if r_total:
            write_rows(d, r_start, removed)
        f.attrs["complete"] = 1  # the last write: a file without it was cut short
    comm.Barrier()
    if comm.Get_rank() == 0:
        os.replace(tmp, path)  # atomic on POSIX: readers see the old or the new file
    comm.Barrier()


def _open(path: Path) -> tuple[h5py.File, dict]:
    """The open checkpoint and its meta, validated (fields present with n_global rows);
    SceneError with one line otherwise."""
    where = f"--restart {path}"
    if not path.is_file():
        raise SceneError(f"{where}: no such checkpoint file")
    f = None
    try:
        f = h5py.File(path, "r")
        if f.attrs.get("format") != FORMAT:
            raise SceneError(f"{where}: not a psph checkpoint (format attribute "
                             f"{f.attrs.get('format')!r}, expected {FORMAT!r})")
        if f.attrs.get("complete") != 1:
            raise SceneError(f"{where}: incomplete checkpoint (the writer was "
                             "interrupted); use the previous one")
        meta = json.loads(f.attrs["meta"])
        n = meta.get("n_global")
        for fld in FIELDS:
            if fld.name in ADDED_FIELDS and fld.name not in f["particles"]:
                continue
            rows = f["particles"][fld.name].shape[0]
            if rows != n:
                raise SceneError(f"{where}: corrupt checkpoint (field {fld.name} has "
                                 f"{rows} rows, expected {n})")
        n_ids = meta.setdefault("n_ids", n)
        if "alive" in f:
            meta["n_removed"] = n_ids - n  # checked against the mask by the reader
        elif "removed_ids" in f:
            meta["n_removed"] = f["removed_ids"].shape[0]
        else:
            meta["n_removed"] = 0
        if n_ids - meta["n_removed"] != n:
            raise SceneError(f"{where}: corrupt checkpoint ({n_ids - meta['n_removed']} ids "
                             f"alive, {n} particles)")
        meta.setdefault("removals_done", 0)
        return f, meta
    except BaseException as e:
        if f is not None:
            f.close()
        if isinstance(e, (OSError, KeyError, ValueError, TypeError)):
            raise SceneError(f"{where}: unreadable checkpoint ({_reason(e)})") from None
        raise


def _removed_rows(f: h5py.File, lo: int, hi: int) -> np.ndarray:
    """Rows lo..hi of the removed ids; of an older file, the ids not alive in the rows
    lo..hi of its `alive` mask (read a chunk at a time)."""
    if "removed_ids" in f:
        return f["removed_ids"][lo:hi].astype(np.int64)
    if "alive" not in f:
        return np.zeros(0, np.int64)
    parts = [np.flatnonzero(f["alive"][a:min(a + CHUNK_ROWS, hi)] == 0) + a
             for a in range(lo, hi, CHUNK_ROWS)]
    return np.concatenate(parts or [np.zeros(0, np.int64)]).astype(np.int64)


def read_checkpoint(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    """(meta, global arrays of every particle field and `removed_ids`), on one process,
    for inspection (a run restarts with `read_restart`). Raises SceneError (exit 2) with
    one line if the file is missing, truncated, incomplete or not a psph checkpoint."""
    path = Path(path)
    f, meta = _open(path)
    try:
        with f:
            n = meta["n_global"]
            arrays = {fld.name: f["particles"][fld.name][()] if fld.name in f["particles"]
                      else np.zeros(n) for fld in _fields(f)}
            n_rows = f["alive"].shape[0] if "alive" in f else meta["n_removed"]
            arrays["removed_ids"] = _removed_rows(f, 0, n_rows)
    except (OSError, KeyError, ValueError) as e:
        raise SceneError(f"--restart {path}: unreadable checkpoint ({_reason(e)})") from None
    return meta, arrays


def _agree(comm, fn, *args, close=None):
    """fn(*args) on every rank (collective); if it raised SceneError on any rank, every
    rank raises the lowest such rank's (after `close(result)` where fn succeeded)."""
    try:
        result, problem = fn(*args), None
    except SceneError as e:
        result, problem = None, str(e)
    problems = [p for p in comm.allgather(problem) if p is not None]
    if problems:
        if close is not None and result is not None:
            close(result)
        raise SceneError(problems[0])
    return result


def read_restart(path: Path, comm, axis: int, min_width: float, chunk: int = CHUNK_ROWS,
                 check: Callable[[dict], None] | None = None,
                 boxes: tuple[int, tuple[int, int]] | None = None
                 ) -> tuple[dict, np.ndarray | tuple, dict[str, np.ndarray], np.ndarray]:
    """Collective: (meta, slab cuts, this rank's particles, this rank's share of the
    removed ids) of the checkpoint `path`. Each rank reads the rows of its share of the
    file, `chunk` rows at a time; the cuts are `slab_cuts` of all positions along `axis`
    (`distributed_cuts`); each row is then sent to its owner, which keeps the file's
    order. With `boxes` = (a1, (n0, n1)) the owners are boxes along two axes
    (`decomposition.boxes`) and the cuts (slab cuts, box cuts0, box cuts1).
    `check(meta)`, if given, runs before the rows are read (it may raise
    SceneError on every rank). SceneError (exit 2, on every rank) if the file is unreadable
    on any rank."""
    from psph.decomposition.boxes import box_cuts
    from psph.decomposition.slabs import distributed_cuts
    from psph.kernels.packing import box_owners

    path = Path(path)
    where = f"--restart {path}"
    rank, size = comm.Get_rank(), comm.Get_size()
    # every rank raises, or none does
    f, meta = _agree(comm, lambda: _open(path), close=lambda r: r[0].close())
    try:
        def unreadable(e: Exception) -> SceneError:
            return SceneError(f"{where}: unreadable checkpoint ({_reason(e)})")

        if check is not None:
            check(meta)  # the same meta everywhere: every rank raises, or none does
        n = meta["n_global"]
        lo, hi = rank * n // size, (rank + 1) * n // size

        axes = [axis] if boxes is None else [axis, boxes[0]]

        def first_pass():
            try:
                coords = np.concatenate([np.zeros((0, len(axes)))] + [
                    f["particles"]["x"][a:min(a + chunk, hi)][:, axes]
                    for a in range(lo, hi, chunk)])
                r_rows = f["alive"].shape[0] if "alive" in f else meta["n_removed"]
                removed = _removed_rows(f, rank * r_rows // size, (rank + 1) * r_rows // size)
            except (OSError, KeyError, ValueError) as e:
                raise unreadable(e) from None
            return coords, removed

        coords, removed = _agree(comm, first_pass)
        n_removed = comm.allreduce(len(removed))
        if n_removed != meta["n_removed"]:
            raise SceneError(f"{where}: corrupt checkpoint ({meta['n_ids'] - n_removed} "
                             f"ids alive, {n} particles)")
        cuts = distributed_cuts(coords[:, 0], size, min_width, comm)
        if boxes is None:
            dest = np.searchsorted(cuts[1:-1], coords[:, 0], side="right")
        else:
            cuts0, cuts1 = box_cuts(comm, coords[:, 0], coords[:, 1], boxes[1])
            dest = np.zeros(len(coords), np.int64)
            box_owners(np.ascontiguousarray(coords), len(coords), 0, 1, cuts0, cuts1, dest)
            cuts = (cuts, cuts0, cuts1)
        del coords
        particles = _to_owners(f, comm, dest, lo, chunk, unreadable)
    finally:
        f.close()
    return meta, cuts, particles, removed


def _to_owners(f: h5py.File, comm, dest: np.ndarray, lo: int, chunk: int, unreadable
               ) -> dict[str, np.ndarray]:
    """This rank's rows (dest == rank) of every field; each rank reads its share (rows
    lo..lo+len(dest)) `chunk` rows at a time and sends every row to rank `dest` (one
    all-to-all a chunk, the same number of them on every rank). Collective."""
    from mpi4py import MPI

    size = comm.Get_size()
    names = [fld.name for fld in _fields(f)]
    widths = [fld.ncomp for fld in _fields(f)]
    col = np.concatenate(([0], np.cumsum(widths)))
    w = int(col[-1])
    send_total = np.bincount(dest, minlength=size).astype(np.int64)
    recv_total = np.zeros(size, np.int64)
    comm.Alltoall(send_total, recv_total)
    out = {nm: np.zeros((int(recv_total.sum()),) + ((k,) if k > 1 else ()))
           for nm, k in zip(names, widths, strict=True)}
    at = np.concatenate(([0], np.cumsum(recv_total)[:-1]))  # next row from each source
    chunk = max(1, min(chunk, EXCHANGE_BYTES // (8 * w)))
    rounds = comm.allreduce(-(-len(dest) // chunk), op=MPI.MAX)
    for i in range(rounds):
        a, b = min(i * chunk, len(dest)), min((i + 1) * chunk, len(dest))
        d = dest[a:b]
        order = np.argsort(d, kind="stable")
        send = np.zeros((max(b - a, 1), w))
        _agree(comm, _pack_chunk, f, lo + a, lo + b, order, send, col, unreadable)
        send_counts = np.bincount(d, minlength=size).astype(np.int64)
        recv_counts = np.zeros(size, np.int64)
        comm.Alltoall(send_counts, recv_counts)
        recv = np.zeros((max(int(recv_counts.sum()), 1), w))
        sd = np.concatenate(([0], np.cumsum(send_counts)[:-1])) * w
        rd = np.concatenate(([0], np.cumsum(recv_counts)[:-1])) * w
        comm.Alltoallv([send, (send_counts * w, sd), MPI.DOUBLE],
                       [recv, (recv_counts * w, rd), MPI.DOUBLE])
        for s_ in range(size):  # each source's rows, in its order, after the earlier ones
            m = int(recv_counts[s_])
            r0 = int(rd[s_]) // w
            for j, nm in enumerate(names):
                out[nm][at[s_]:at[s_] + m] = recv[r0:r0 + m, col[j]:col[j + 1]].reshape(
                    (m,) + out[nm].shape[1:])
        at += recv_counts
    return out


def _pack_chunk(f: h5py.File, a: int, b: int, order: np.ndarray, send: np.ndarray,
                col: np.ndarray, unreadable) -> None:
    """Rows a..b of every field, in `order`, into the columns `col` of `send`."""
    try:
        for j, fld in enumerate(_fields(f)):
            if fld.name in f["particles"]:
                rows = f["particles"][fld.name][a:b]
                # (b - a, width): also for an empty slice, where reshape(0, -1) fails
                send[:b - a, col[j]:col[j + 1]] = rows.reshape(
                    b - a, col[j + 1] - col[j])[order]
    except (OSError, KeyError, ValueError) as e:
        raise unreadable(e) from None


def _fields(f: h5py.File) -> tuple:
    """The particle fields of a checkpoint, with the widths of its dimension."""
    parts = f["particles"]
    recycle = parts["recycle_x"].shape[1] if "recycle_x" in parts else 0
    return fields_of_dim(int(parts["x"].shape[1]), recycle)


def _reason(e: Exception) -> str:
    text = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
    return text[:160]


def read_history(path: Path) -> list[dict]:
    """The diagnostics rows saved with a checkpoint (read_checkpoint has validated it)."""
    with h5py.File(path, "r") as f:
        return json.loads(f["history_json"][()].tobytes().decode() or "[]")

"""Room on the output file system, checked before each collective write.

A collective HDF5 write that runs out of space mid-way fails on one rank and leaves the
others inside MPI-IO (seen: two ranks spinning for minutes on a full 3 MB tmpfs, nothing
printed). So every snapshot and checkpoint first asks whether its bytes fit: rank 0 reads
the free space of the directory's file system, all ranks get the verdict and, when it does
not fit, raise the same `OutputError` together (exit 74, one line) before any of them
starts the write. A quota the file system does not report is still caught by the write's
own error on a single rank, or on every rank when they all fail.
"""

from __future__ import annotations

import os
from pathlib import Path

from psph.errors import OutputError

# id, x, u, v, p, n, stress, eps_p, plastic_work, vol, material
SNAPSHOT_ROW_BYTES = 8 * (1 + 2 + 2 + 2 + 1 + 1 + 6 + 1 + 1 + 1 + 1)
SLACK_BYTES = 1 << 18  # HDF5 metadata and attributes (the side files are small)


def free_bytes(directory: Path) -> int:
    """Bytes an unprivileged writer may still use on `directory`'s file system."""
    st = os.statvfs(directory)
    return st.f_bavail * st.f_frsize


def require_space(path: Path, nbytes: int, comm, resume_hint: str) -> None:
    """Collective: raise OutputError on every rank if `nbytes` (plus slack) do not fit
    next to `path`. resume_hint: what the user can do, e.g. the last checkpoint."""
    problem = None
    if comm.Get_rank() == 0:
        need = int(nbytes) + SLACK_BYTES
        try:
            free = free_bytes(Path(path).parent)
        except OSError as e:
            problem = f"cannot write {path}: {e.strerror}"
        else:
            if free < need:
                problem = (f"cannot write {path}: {need / 1e6:.1f} MB needed, "
                           f"{free / 1e6:.1f} MB free on its file system (no space left "
                           f"on device)")
        if problem is not None:
            problem += f"; {resume_hint}"
    problem = comm.bcast(problem, root=0)
    if problem is not None:
        raise OutputError(problem)

"""Will the scene's particles fit in this node's memory? Checked before a run reads a
checkpoint, seeds a particle or writes anything: a scene whose particle count would not
fit is bad input (exit 2, one line, nothing written), not a crash hours into a job."""

from psph.errors import SceneError
from psph.geometry.lattice import estimate_count

# Bytes a particle at least, by (dim, coupled): the running state per owned particle
# (`Simulation.state_bytes`: the particle store, scratch, neighbour and pair lists) as
# `make bench` measures it (docs/performance.md): the coupled elastic TPI step 929-945 B
# in 2D; in 3D 2,330 B at h = 1.2 dx (every shipped 3D scene's) and 2,793-3,315 B at
# 1.3 dx; the dry 3D collapse 1,088-1,375 B; a dry 2D scene 688 B. Rounded down: the peak
# resident memory is above the state (the interpreter, numba and MPI, about 190 MB a
# rank; the snapshot and checkpoint writes; the projection's per-pair weights), so the
# check refuses only what clearly cannot run.
STATE_BYTES_PER_PARTICLE = {(2, True): 900, (2, False): 650, (3, True): 2_300,
                            (3, False): 1_000}

GIB = 1024.0 ** 3


def available_bytes(meminfo: str = "/proc/meminfo") -> float | None:
    """MemAvailable of this node (bytes), or None where /proc/meminfo cannot tell."""
    try:
        with open(meminfo) as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0  # given in kB
    except (OSError, ValueError, IndexError):
        return None
    return None


def node_ranks(comm) -> int:
    """How many ranks of `comm` share this rank's node (its memory; collective)."""
    from mpi4py import MPI

    try:
        node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    except (MPI.Exception, NotImplementedError, AttributeError):
        return comm.Get_size()
    try:
        return node.Get_size()
    finally:
        node.Free()


def check_memory(scene, comm, available: float | None = None) -> None:
    """SceneError (exit 2) on every rank if the scene's estimated particle count
    (`estimate_count`) times STATE_BYTES_PER_PARTICLE, shared evenly among the ranks,
    exceeds the memory available on some node to the ranks it holds (collective: one
    allgather, the same verdict and line everywhere). `available`: this node's bytes
    (default MemAvailable from /proc/meminfo; unknown: no check on that node)."""
    count = estimate_count(scene)
    size = comm.Get_size()
    local = node_ranks(comm)
    coupled = scene.pressure.scheme != "none"
    per_particle = STATE_BYTES_PER_PARTICLE[scene.dim, coupled]
    per_rank = count * per_particle / size
    avail = available_bytes() if available is None else available
    nodes = comm.allgather((local, avail))
    short = [(loc, av) for loc, av in nodes if av is not None and per_rank * loc > av]
    if not short:
        return
    loc, av = min(short, key=lambda n: n[1] / n[0])
    node = "" if loc == 1 else f", {per_rank * loc / GIB:.3g} GiB for the {loc} on one node"
    raise SceneError(
        f"scene '{scene.name}': particles.dx = {scene.particles.dx!r}: about {count:.3g} "
        f"particles (an estimate from the sources' volumes) at {per_particle} B each (the "
        f"running state measured in {scene.dim}D, {'coupled' if coupled else 'dry'}) need "
        f"{per_rank / GIB:.3g} GiB a rank on {size} rank(s){node}, more than the "
        f"{av / GIB:.3g} GiB the node has available (MemAvailable): take a larger dx, or "
        "more nodes")

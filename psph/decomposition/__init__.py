"""Domain decomposition: slabs, halo exchange, migration. All mpi4py use lives here (and
in psph/io for collective HDF5)."""

from psph.decomposition.slabs import Slabs

__all__ = ["Slabs"]

"""psph: MPI-parallel SPH for coupled flow-deformation of saturated soils."""

__version__ = "0.1.0"

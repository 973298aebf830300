"""Numba kernels: pure functions over arrays and scalars. No MPI, no I/O, no globals."""

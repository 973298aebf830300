"""Output: parallel HDF5 snapshots, XDMF sidecar, diagnostics history, summary."""

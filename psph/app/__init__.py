"""The application: command line, the run driver (outputs, checkpoints, restarts, stop
signals), the restart rule, progress, and experiment entry points that run scenes."""

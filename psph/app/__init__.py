"""The application: command line, the run driver (outputs, checkpoints, restarts, stop
signals), the restart rule, the memory check and progress."""

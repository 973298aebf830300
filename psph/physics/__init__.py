"""Physics of one step, free of MPI: material constants, time-step limits, loads, the
initial state and non-local softening."""

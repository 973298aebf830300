"""Physics of one step, free of MPI: material constants, loads, initial state, stages."""

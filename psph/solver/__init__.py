"""The step pipeline: the Simulation (set-up and stages), the time stepping, the pressure
solve of the projection and its conjugate gradients, polyline boundaries and drainage."""

"""The two-layer column at rest under gravity of `tests/test_materials.py` (the same
scene text and the same odd-even filter), for `oddeven_stress_mode.py`."""

import numpy as np

LAYERED = """
name = "two_layers"
gravity = [0.0, -9.81]
[domain]
min = [0.0, 0.0]
max = [0.4, 2.0]
[particles]
dx = 0.05
[[particles.blocks]]
min = [0.0, 0.0]
max = [0.4, 1.0]
material = "dense"
[[particles.blocks]]
min = [0.0, 1.0]
max = [0.4, 2.0]
material = "light"
[[materials]]
name = "dense"
E = 20.0e6
nu = 0.33
porosity = 0.35
rho_s = 2650.0
k = 2.0e-4
[[materials]]
name = "light"
E = 20.0e6
nu = 0.33
porosity = 0.5
rho_s = 1800.0
k = 2.0e-4
[boundaries]
left = { motion = "slip" }
right = { motion = "slip" }
bottom = { motion = "fixed" }
top = { motion = "free", flow = "drained" }
[initial]
water_table = 1.975
k0 = 0.5
[pressure]
scheme = "explicit"
drained_boundary = "layer"
[time]
end = 0.05
[output]
interval = 0.05
[stabilisation]
damping = 0.02
"""


def row_pairs(a, x0, y0):
    """Mean of each particle and the one below it in its lattice column: takes out the
    odd-even (zig-zag) mode of sigma' on the lattice (README, issue 13)."""
    order = np.lexsort((y0, np.round(x0, 9)))
    b = a[order]
    same = np.isclose(x0[order][1:], x0[order][:-1])
    return 0.5 * (b[1:] + b[:-1])[same]

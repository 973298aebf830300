"""Which share of a particle's weight the surface floor's `weight_friction` should add
(issue 37, docs/vv/collapse_3d.md, "the floor's friction"): the block of
`psph.app.floor_friction` sliding on collapse_3d's floor, n = 2, 4, 8 rows thick,
with the floor's weight friction at full strength (the rule as it is), at half strength
and off; the deceleration over g tan(phi_b); then the same in 2D on a friction polyline
(whose wall limit still reads the Shepard-averaged stress above the line).

    .venv/bin/python bench/diagnostics/surface_floor_sliding.py   # ~1.5 min, one rank
"""

import math

from psph.app.floor_friction import PHI_B, block_deceleration


def main() -> None:
    g_tan = 9.81 * math.tan(math.radians(PHI_B))
    print(f"deceleration / g tan(phi_b) (= {g_tan:.2f} m/s^2)")
    print("| rows | weight friction full | half | off |")
    print("|---|---|---|---|")
    for dim in (3, 2):
        for rows in (2, 4, 8):
            cells = [block_deceleration(rows, share, dim) / g_tan
                     for share in (1.0, 0.5, 0.0)]
            print(f"| {rows} ({dim}D) | " + " | ".join(f"{c:.3f}" for c in cells) + " |",
                  flush=True)


if __name__ == "__main__":
    main()

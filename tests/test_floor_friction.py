"""The friction surface's Coulomb law in a run (issue 37): a block sliding on
`collapse_3d`'s floor decelerates at g tan(phi_b), its weight's friction counted once
(`bench/studies/floor_friction.py`, which prints the table over thicknesses and rules)."""

import math

import pytest

from bench.studies.floor_friction import PHI_B, block_deceleration


@pytest.mark.parametrize("rows", [2, 4])
def test_a_block_on_a_friction_surface_decelerates_at_g_tan_phi_b(rows):
    """Measured: 1.109 (2 rows) and 0.918 (4 rows) of g tan(phi_b). Before the wall's
    limit read the normal stress at the surface and the weight friction counted only
    the weight a particle's stress does not carry: 1.214 and 1.144 (the weight counted
    twice); with the stress-based limit alone, as it was, 0.698 and 0.778."""
    ratio = block_deceleration(rows) / (9.81 * math.tan(math.radians(PHI_B)))
    assert ratio == pytest.approx(1.0, abs=0.13)

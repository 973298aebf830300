"""Counting successive slides from the back-scarp history (Section 4.5 metrics)."""

import numpy as np

from psph.verify.collapse import successive_slides


def test_two_retreats_separated_by_a_pause_are_two_slides():
    t = np.arange(10.0)
    scarp = np.array([140, 140, 133, 130, 130, 130, 124, 124, 124, 124], float)
    got = successive_slides(t, scarp, 20.0, min_retreat=2.0)
    assert got["slides"] == 2
    assert got["slide_times_s"] == [2.0, 6.0]
    assert got["slide_scarps_m"] == [130.0, 124.0]


def test_debris_moving_back_and_small_wiggles_are_not_slides():
    t = np.arange(8.0)
    # 139.5: below the 2 m threshold; 145: debris flowing back does not undo a retreat
    scarp = np.array([140, 139.5, 139.5, 145, 139.5, 139.5, 130, 130], float)
    got = successive_slides(t, scarp, 20.0, min_retreat=2.0)
    assert got["slides"] == 1 and got["slide_scarps_m"] == [130.0]


def test_a_retreat_still_running_at_the_end_counts():
    got = successive_slides(np.arange(4.0), np.array([140.0, 140.0, 137.0, 131.0]), 20.0, 2.0)
    assert got["slides"] == 1 and got["slide_scarps_m"] == [131.0]

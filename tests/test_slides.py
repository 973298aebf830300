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
    scarp = np.array([140.0, 140.0, 140.0, 140.0, 137.0, 131.0])
    got = successive_slides(np.arange(6.0), scarp, 20.0, 2.0)
    assert got["slides"] == 1 and got["slide_scarps_m"] == [131.0]


def test_bursts_over_a_creeping_scarp_are_the_slides():
    """The K0 = 0.5 slope's scarp (2026-11-29, snapshots every 1 s): it creeps back at
    0.8-4.8 m/s and jumps 11-14 m in five seconds. Each jump is a slide; the creep is not
    (the old rule, a slide ends with a snapshot without retreat, counted one)."""
    scarp = np.array([143.4, 141.8, 129.8, 126.6, 125.8, 123.4, 118.6, 107.4, 105.0, 102.6,
                      99.4, 96.2, 92.2, 81.0, 79.4, 77.0, 73.0, 70.6, 57.0, 53.8, 52.2, 49.0,
                      45.8, 34.6, 30.6, 29.0, 25.8, 22.6, 19.4, 15.4, 12.2, 8.2, 4.2, 0.2,
                      0.2, 0.2, 0.2, 0.2, 0.2, 0.2, 0.2])
    got = successive_slides(np.arange(41.0), scarp, 20.0, 2.0)
    assert got["slides"] == 5
    assert got["slide_times_s"] == [2.0, 7.0, 13.0, 18.0, 23.0]
    assert got["slide_rate_threshold_m_per_s"] == 6.4

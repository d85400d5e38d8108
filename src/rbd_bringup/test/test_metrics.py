import math

import pytest

from rbd_bringup.metrics import ContactMonitor, footprint_clearance


def test_clearance_in_front_and_to_the_side():
    # Person of radius 0.2 m, 1.0 m ahead of a 0.5 x 0.3 footprint: 1.0 - 0.25 - 0.2.
    assert footprint_clearance((0, 0), 0.0, (1.0, 0.0), 0.2) == pytest.approx(0.55)
    assert footprint_clearance((0, 0), 0.0, (0.0, 1.0), 0.2) == pytest.approx(1.0 - 0.15 - 0.2)


def test_clearance_follows_heading():
    # Robot turned 90 degrees: the person ahead in the world is now beside it.
    assert footprint_clearance((0, 0), math.pi / 2, (0.0, 1.0), 0.2) == pytest.approx(0.55)
    assert footprint_clearance((0, 0), math.pi / 2, (1.0, 0.0), 0.2) == pytest.approx(0.65)


def test_corner_distance_is_euclidean():
    d = footprint_clearance((0, 0), 0.0, (0.25 + 0.3, 0.15 + 0.4), 0.0)
    assert d == pytest.approx(0.5)


def test_contact_is_non_positive():
    assert footprint_clearance((0, 0), 0.0, (0.4, 0.0), 0.2) < 0
    assert footprint_clearance((0, 0), 0.0, (0.0, 0.0), 0.2) < 0


def test_bad_sizes_rejected():
    with pytest.raises(ValueError):
        footprint_clearance((0, 0), 0.0, (1, 1), -0.1)


def test_monitor_counts_each_contact_once_and_tracks_minimum():
    mon = ContactMonitor()
    mon.update(0.0, (0, 0), 0.0, [("p1", 2.0, 0.0, 0.2)])
    mon.update(0.1, (0, 0), 0.0, [("p1", 0.3, 0.0, 0.2)])
    mon.update(0.2, (0, 0), 0.0, [("p1", 0.3, 0.0, 0.2)])
    mon.update(0.3, (0, 0), 0.0, [("p1", 2.0, 0.0, 0.2)])
    mon.update(0.4, (0, 0), 0.0, [("p1", 0.3, 0.0, 0.2)])
    assert [c[0] for c in mon.contacts] == [0.1, 0.4]
    assert mon.min_clearance == pytest.approx(0.3 - 0.25 - 0.2)
    assert mon.min_clearance_at == 0.1


def test_footprint_box_clearance_against_hand_geometry():
    from rbd_bringup.metrics import footprint_box_clearance, outside_polygon

    # A1 at the origin facing +x: its front edge at x = 0.25; a 0.4 m box whose face is at x = 0.55.
    assert footprint_box_clearance((0.0, 0.0), 0.0, (0.75, 0.0), 0.0, (0.4, 0.4)) == pytest.approx(0.30)
    # Turned by 90 deg the footprint reaches only 0.15 m ahead.
    assert footprint_box_clearance((0.0, 0.0), math.pi / 2, (0.75, 0.0), 0.0, (0.4, 0.4)) == pytest.approx(0.40)
    # Corner to corner: box at (1, 1) rotated 45 deg, its corner at 1 - 0.2 * sqrt(2) on the diagonal.
    d = footprint_box_clearance((0.0, 0.0), 0.0, (1.0, 1.0), math.pi / 4, (0.4, 0.4))
    # The box's near edge lies on x + y = 2 - 0.2 sqrt(2); the footprint's corner (0.25, 0.15) faces it.
    assert d == pytest.approx((2 - 0.2 * math.sqrt(2) - 0.25 - 0.15) / math.sqrt(2))
    assert footprint_box_clearance((0.0, 0.0), 0.0, (0.4, 0.0), 0.0, (0.4, 0.4)) == 0.0  # overlapping
    assert footprint_box_clearance((0.0, 0.0), 0.0, (0.0, 0.0), 0.0, (0.1, 0.1)) == 0.0  # box under the robot
    square = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    assert not outside_polygon((0.5, 0.5), square) and outside_polygon((1.5, 0.0), square)


def test_box_ahead_puts_the_box_gap_ahead_of_the_footprint():
    from rbd_bringup.metrics import box_ahead, footprint_box_clearance

    # A1 at the origin facing +x, front edge at x = 0.25: a 0.4 m box 0.5 m ahead has its centre at 0.95.
    x, y, yaw = box_ahead((0.0, 0.0, 0.0), 0.5, (0.4, 0.4))
    assert (x, y, yaw) == pytest.approx((0.95, 0.0, 0.0), abs=1e-6)
    # Turned 45 deg, its corner leads: half diagonal 0.2 sqrt(2) behind the centre.
    x, _, yaw = box_ahead((0.0, 0.0, 0.0), 0.5, (0.4, 0.4), box_yaw=math.pi / 4)
    assert x == pytest.approx(0.75 + 0.2 * math.sqrt(2.0), abs=1e-6) and yaw == pytest.approx(math.pi / 4)
    # Robot at (1, 2) facing +y, box 0.1 m to its left (-x in the world): centre at y = 2 + 0.25 + 0.3 + 0.2.
    x, y, yaw = box_ahead((1.0, 2.0, math.pi / 2), 0.3, (0.4, 0.4), lateral=0.1, box_yaw=0.3)
    assert footprint_box_clearance((1.0, 2.0), math.pi / 2, (x, y), yaw, (0.4, 0.4)) == pytest.approx(0.3, abs=1e-6)
    assert x == pytest.approx(0.9) and yaw == pytest.approx(math.pi / 2 + 0.3)
    assert box_ahead((1.0, 2.0, math.pi / 2), 0.3, (0.4, 0.4), lateral=0.1)[1] == pytest.approx(2.75, abs=1e-6)


def test_box_ahead_rejects_bad_input():
    from rbd_bringup.metrics import box_ahead

    for bad in ((0.0, (0.4, 0.4), 0.0), (-0.1, (0.4, 0.4), 0.0), (0.5, (0.0, 0.4), 0.0),
                (float("nan"), (0.4, 0.4), 0.0), (0.3, (0.4, 0.4), 1.0)):  # the last: 1 m beside the robot
        with pytest.raises(ValueError):
            box_ahead((0.0, 0.0, 0.0), bad[0], bad[1], lateral=bad[2])


def test_towards_monitor_flags_motion_towards_a_moving_person_after_the_reaction_time():
    from rbd_bringup.metrics import TowardsMonitor

    m = TowardsMonitor(band=0.5, reaction=0.5)
    # A person walks at 0.5 m/s towards the front of a robot that backs away: never a violation.
    for i in range(20):
        t = 0.1 * i
        m.update(t, (0.0, 0.0), 0.0, (-0.1, 0.0), [("p", 1.0 - 0.05 * i, 0.0, 0.2, -0.5, 0.0)])
    assert m.violations == [] and m.checked > 0 and m.max_towards < 0.0
    # Walking into a person who walks across its way 0.3 m ahead: allowed for the reaction time only.
    m = TowardsMonitor(band=0.5, reaction=0.5)
    for i in range(10):
        m.update(0.1 * i, (0.0, 0.0), 0.0, (0.2, 0.0), [("p", 0.75, 0.5 - 0.1 * i, 0.2, 0.0, -1.0)])
    assert [round(t, 1) for t, _, _ in m.violations] == [0.5, 0.6, 0.7, 0.8, 0.9]
    assert m.max_towards == pytest.approx(0.2, abs=0.05)
    # A person standing still (or far away) is not a moving person: nothing is checked.
    m = TowardsMonitor()
    m.update(0.0, (0.0, 0.0), 0.0, (0.2, 0.0), [("p", 0.7, 0.0, 0.2, 0.0, 0.0), ("q", 3.0, 0.0, 0.2, -1.0, 0.0)])
    m.update(1.0, (0.0, 0.0), 0.0, (0.2, 0.0), [("p", 0.7, 0.0, 0.2, 0.0, 0.0), ("q", 3.0, 0.0, 0.2, -1.0, 0.0)])
    assert m.checked == 0 and m.violations == []

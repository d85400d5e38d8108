import math

import pytest

from rbd_bringup.demo_report import StopOnsets, build_report, percentile, reaction_times, render_text, stop_demanded


def test_reaction_time_from_moving_command_to_first_zero():
    cmds = [(0.0, 0.3), (0.1, 0.3), (0.2, 0.3), (0.25, 0.0), (0.3, 0.0)]
    assert reaction_times([0.12], cmds) == [pytest.approx(0.13)]


def test_onset_while_standing_is_not_a_reaction():
    cmds = [(0.0, 0.0), (0.1, 0.0), (0.2, 0.3)]
    assert reaction_times([0.05], cmds) == []


# rbd_msgs/CollisionState.msg: points[4] indexed FRONT, LEFT, BACK, RIGHT; HighCmd velocity[0] forward,
# velocity[1] left (Unitree's body frame).
LEFT_INTRUDED = (0, 5, 0, 0)


def test_guarded_motion_away_from_the_intruder_is_no_stop_but_a_trick_motion_is():
    to_the_right = (-0.01, -0.12, 0.0)
    assert not stop_demanded(True, LEFT_INTRUDED, to_the_right, "ESCAPING")
    assert not stop_demanded(True, LEFT_INTRUDED, to_the_right, "DODGING")
    assert stop_demanded(True, LEFT_INTRUDED, to_the_right, "EXECUTING")
    assert stop_demanded(True, LEFT_INTRUDED, to_the_right, "AVOIDING")  # detour poses stop on the flag


def test_guarded_motion_towards_the_intruder_or_turning_must_stop():
    assert stop_demanded(True, LEFT_INTRUDED, (0.0, 0.12, 0.0), "ESCAPING")
    assert stop_demanded(True, (0, 0, 7, 0), (-0.1, 0.0, 0.0), "DODGING")
    assert stop_demanded(True, (0, 0, 7, 0), (0.0, 0.0, 0.2), "ESCAPING")  # a turn sweeps every side
    assert not stop_demanded(True, (0, 4, 0, 0), (0.0, 0.12, 0.0), "ESCAPING")  # below the threshold


def _escape_run(velocity, slow):
    """The demo's round-3 p99 case: ESCAPING to one side while the wall is on the LEFT; the A1 gets
    ``velocity`` until 1.58 s after the intrusion (``slow``) or one command after it."""
    stops = StopOnsets()
    stops.update(0.0, False, (0, 1, 0, 0), True, velocity, "ESCAPING")
    stops.update(0.1, True, LEFT_INTRUDED, True, velocity, "ESCAPING")
    stops.update(0.2, True, (0, 0, 0, 0), True, velocity, "ESCAPING")
    zero_at = 0.1 + (1.58 if slow else 0.03)
    cmds = [(0.02 * i, 0.0 if 0.02 * i >= zero_at else 0.12) for i in range(100)]
    return reaction_times(stops.onsets, cmds)


def test_escape_away_from_the_wall_is_not_timed_as_a_reaction():
    assert _escape_run((-0.01, -0.12, 0.0), slow=True) == []


def test_a_slow_stop_towards_the_intruder_is_caught():
    assert _escape_run((0.0, 0.12, 0.0), slow=True) == [pytest.approx(1.58, abs=0.021)]
    assert _escape_run((0.0, 0.12, 0.0), slow=False) == [pytest.approx(0.03, abs=0.021)]


def test_stale_readings_are_no_onset_and_a_held_stop_counts_once():
    stops = StopOnsets()
    assert not stops.update(0.0, True, (9, 0, 0, 0), False, (0.3, 0.0, 0.0), "EXECUTING")
    assert stops.update(0.1, True, (9, 0, 0, 0), True, (0.3, 0.0, 0.0), "EXECUTING")
    assert not stops.update(0.2, True, (9, 0, 0, 0), True, (0.0, 0.0, 0.0), "COLLISION_DETECTED")
    assert stops.onsets == [0.1]


def test_percentile_nearest_rank():
    assert percentile([], 50) is None
    assert percentile([3.0, 1.0, 2.0], 50) == 2.0
    assert percentile([1.0, 2.0, 3.0, 4.0], 99) == 4.0


def test_report_counts_stops_resumes_and_pose_error():
    log = [(0, "EMERGENCY_STOP"), (1, "WAITING_FOR_GESTURE"), (2, "GENERATING_PATH"), (3, "EXECUTING"),
           (4, "COLLISION_DETECTED"), (6, "EXECUTING"), (9, "WAITING_FOR_GESTURE")]
    rep = build_report(["walk"], ["walk"], [], 0.42, log, (0, 0, 0), (0.03, 0.04, math.radians(2)), [0.1, 0.12],
                       0.1, 12.0)
    assert rep["stops"] == 2 and rep["resumes"] == 1 and rep["collision_stops"] == 1
    assert rep["final_position_error_m"] == pytest.approx(0.05)
    assert rep["final_yaw_error_deg"] == pytest.approx(2.0, abs=0.01)
    assert rep["reaction_p99_s"] == pytest.approx(0.12)
    assert rep["reaction_goal_s"] == pytest.approx(0.12)
    text = render_text(rep)
    assert "collisions with people:  0" in text and "1 of 1" in text


def test_report_counts_avoided_obstacles_and_time_blocked():
    log = [(0, "WAITING_FOR_GESTURE"), (1, "GENERATING_PATH"), (2, "EXECUTING"), (4, "COLLISION_DETECTED"),
           (5, "BLOCKED"), (8, "ESCAPING"), (11, "AVOIDING"), (20, "EXECUTING"), (30, "COLLISION_DETECTED"),
           (32, "EXECUTING"), (40, "WAITING_FOR_GESTURE")]
    events = ["blocked: unmoved", "escaped: clear", "plan: 2 waypoints", "avoided: reached", "gave_up: goal blocked"]
    rep = build_report(["stroll"], ["stroll"], [], 1.0, log, (0, 0, 0), (0, 0, 0), [], 0.1, 40.0,
                       avoidance_events=events, obstacle_contacts=[(12.0, "bag")], min_obstacle_clearance=0.0)
    assert rep["obstacles_avoided"] == 1 and rep["avoidance_gave_up"] == ["gave_up: goal blocked"]
    assert rep["time_blocked_s"] == pytest.approx(1 + 3 + 2)  # COLLISION_DETECTED 4-5, 30-32; BLOCKED 5-8
    assert rep["time_avoiding_s"] == pytest.approx(3 + 9)
    assert rep["collisions_with_obstacles"] == 1 and rep["min_distance_to_obstacle_m"] == 0.0
    text = render_text(rep)
    assert "obstacles avoided:       1 (1 pose(s) skipped)" in text and "time blocked:            6.0 s" in text

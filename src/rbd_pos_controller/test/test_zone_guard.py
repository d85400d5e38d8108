"""The per-side zone gate of guarded (avoidance) goals, and GUARDED in the position controller.

Side indices are rbd_msgs/CollisionState's FRONT=0, LEFT=1, BACK=2, RIGHT=3 (tests/test_msgs.py
checks the message); the occupancy rule is rbd_lidar's (>= point_threshold critical points).
"""

import math

import pytest

from rbd_geometry.goal import Goal
from rbd_pos_controller.controller import PositionController
from rbd_pos_controller.fsm import State
from rbd_pos_controller.goal import GoalRejectedError
from rbd_pos_controller.kinematic_sim import KinematicRobot
from rbd_pos_controller.zone_guard import BACK, FRONT, LEFT, RIGHT, ZoneGuard, cap_speed, sides_towards

CLEAR = [0, 0, 0, 0]
WALL_AHEAD = [40, 0, 0, 0]


def test_sides_towards_each_direction_and_turning_sweeps_all():
    assert sides_towards(0.1, 0.0, 0.0) == {FRONT}
    assert sides_towards(-0.1, 0.0, 0.0) == {BACK}
    assert sides_towards(0.0, 0.1, 0.0) == {LEFT}
    assert sides_towards(0.0, -0.1, 0.0) == {RIGHT}
    assert sides_towards(-0.1, -0.1, 0.0) == {BACK, RIGHT}
    assert sides_towards(0.0, 0.0, 0.2) == {FRONT, LEFT, BACK, RIGHT}
    assert sides_towards(0.0, 0.0, 0.0) == set()


def test_guard_blocks_only_the_sides_moved_towards():
    g = ZoneGuard(point_threshold=5, clear_scans=3, timeout=0.35)
    for i in range(3):
        g.update(0.1 * i, WALL_AHEAD)
    now = 0.25
    assert g.blocked_sides(now) == {FRONT}
    assert not g.allows((0.1, 0.0, 0.0), now)  # into the wall
    assert not g.allows((0.1, 0.1, 0.0), now)  # diagonally into it
    assert g.allows((-0.1, 0.0, 0.0), now)  # away from it
    assert g.allows((0.0, 0.1, 0.0), now)  # along it
    assert not g.allows((-0.1, 0.0, 0.3), now)  # turning sweeps the front
    assert g.filter((0.2, 0.0, 0.0), now) == (0.0, 0.0, 0.0)
    assert g.filter((-0.2, 0.0, 0.0), now) == (-0.2, 0.0, 0.0)


def test_guard_threshold_is_the_collision_rule():
    g = ZoneGuard(point_threshold=5, clear_scans=1)
    g.update(0.0, [4, 0, 0, 0])
    assert g.allows((0.1, 0.0, 0.0), 0.05)  # 4 points: not occupied (rbd_lidar needs 5)
    g.update(0.1, [5, 0, 0, 0])
    assert not g.allows((0.1, 0.0, 0.0), 0.15)


def test_guard_releases_a_side_only_after_clear_scans():
    g = ZoneGuard(point_threshold=5, clear_scans=3)
    g.update(0.0, [0, 0, 9, 0])
    for i, expect in enumerate((False, False, True)):
        g.update(0.1 * (i + 1), CLEAR)
        assert g.allows((-0.1, 0.0, 0.0), 0.1 * (i + 1)) == expect, i


def test_guard_blocks_everything_when_stale_invalid_or_silent():
    g = ZoneGuard(point_threshold=5, clear_scans=1, timeout=0.35)
    assert g.blocked_sides(0.0) == {FRONT, LEFT, BACK, RIGHT}  # no reading yet
    g.update(0.0, CLEAR)
    assert g.allows((0.1, 0.0, 0.0), 0.1)
    assert not g.allows((0.1, 0.0, 0.0), 0.5)  # reading too old
    g.update(0.5, CLEAR, stale=True)
    assert not g.allows((-0.1, 0.0, 0.0), 0.55)
    g.update(0.6, CLEAR, error="missing range field")
    assert not g.allows((0.0, 0.1, 0.0), 0.65)
    g.update(0.7, CLEAR)
    assert g.allows((0.0, 0.1, 0.0), 0.75)  # one clear scan releases with clear_scans=1
    assert g.allows((0.0, 0.0, 0.0), 5.0)  # standing still is always allowed
    with pytest.raises(ValueError):
        ZoneGuard(point_threshold=0)
    with pytest.raises(ValueError):
        ZoneGuard(timeout=float("nan"))


def test_cap_speed_keeps_direction():
    vx, vy = cap_speed(0.3, 0.4, 0.1)
    assert math.hypot(vx, vy) == pytest.approx(0.1)
    assert vx / vy == pytest.approx(0.75)
    assert cap_speed(0.05, 0.0, 0.1) == (0.05, 0.0)


def guarded_controller(points=CLEAR, clear_scans=1):
    ctl = PositionController(guard=ZoneGuard(point_threshold=5, clear_scans=clear_scans, timeout=0.35))
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    ctl.update_zone(0.0, points)
    return ctl


def drive(ctl, robot, t0, seconds, points, dt=0.05):
    """Closed loop on the kinematic robot, feeding a zone reading every 0.1 s; returns the end time."""
    t = t0
    while t < t0 + seconds:
        if int(round(t / dt)) % 2 == 0:
            ctl.update_zone(t, points)
        ctl.update_pose(robot.x, robot.y, robot.yaw, t)
        robot.command(*ctl.step(t))
        robot.advance(dt)
        t += dt
    return t


def test_guarded_goal_backs_away_from_a_wall_without_turning_and_goes_idle():
    ctl = guarded_controller(WALL_AHEAD)
    ctl.set_guarded_goal(Goal(-0.3, 0.0, 2.0), 0.15, 0.0)  # the goal's yaw is ignored
    assert ctl.state == State.GUARDED and ctl.status == "running"
    robot = KinematicRobot()
    peak = 0.0
    t = 0.0
    while ctl.state == State.GUARDED and t < 10.0:
        ctl.update_zone(t, WALL_AHEAD)
        ctl.update_pose(robot.x, robot.y, robot.yaw, t)
        cmd = ctl.step(t)
        assert cmd[2] == 0.0 and cmd[0] <= 0.0  # never towards the wall, never turning
        peak = max(peak, math.hypot(cmd[0], cmd[1]))
        robot.command(*cmd)
        robot.advance(0.05)
        t += 0.05
    assert ctl.state == State.WAITING_FOR_POSE and ctl.status == "idle"
    assert robot.x == pytest.approx(-0.3, abs=0.03)
    assert robot.yaw == pytest.approx(0.0, abs=1e-9)
    assert peak == pytest.approx(0.15, abs=1e-6)  # capped


def test_guarded_goal_stops_when_its_direction_closes_and_goes_on_after_the_hysteresis():
    ctl = guarded_controller(CLEAR, clear_scans=3)
    ctl.update_zone(0.0, CLEAR)
    ctl.update_zone(0.01, CLEAR)
    ctl.update_zone(0.02, CLEAR)
    ctl.set_guarded_goal(Goal(-0.5, 0.0, 0.0), 0.2, 0.02)
    robot = KinematicRobot()
    t = drive(ctl, robot, 0.02, 1.0, CLEAR)
    assert ctl.last_command[0] < 0.0  # backing
    behind = [0, 0, 12, 0]  # someone steps in behind
    ctl.update_zone(t, behind)
    assert ctl.step(t) == (0.0, 0.0, 0.0)
    robot.command(0.0, 0.0, 0.0)
    x_stop = robot.x
    t = drive(ctl, robot, t, 1.0, behind)
    assert robot.x == pytest.approx(x_stop, abs=1e-9)
    assert ctl.state == State.GUARDED  # waits, goal kept
    for _ in range(2):  # 2 clear readings: still held (3 needed)
        ctl.update_zone(t, CLEAR)
        ctl.update_pose(robot.x, robot.y, robot.yaw, t)
        assert ctl.step(t) == (0.0, 0.0, 0.0)
        t += 0.1
    ctl.update_zone(t, CLEAR)
    ctl.update_pose(robot.x, robot.y, robot.yaw, t)
    assert ctl.step(t)[0] < 0.0  # the third releases it
    drive(ctl, robot, t, 6.0, CLEAR)
    assert ctl.state == State.WAITING_FOR_POSE
    assert robot.x == pytest.approx(-0.5, abs=0.03)


def test_guarded_goal_holds_still_on_a_stale_zone_and_ignores_the_slowdown_scale():
    ctl = guarded_controller(WALL_AHEAD)
    ctl.set_speed_scale(0.0)  # rbd_lidar publishes 0 while the wall is in the zone
    ctl.set_guarded_goal(Goal(0.0, -0.3, 0.0), 0.1, 0.0)
    ctl.update_zone(0.05, WALL_AHEAD)
    vx, vy, wz = ctl.step(0.05)
    assert vy < 0.0 and vx == pytest.approx(0.0, abs=1e-9) and wz == 0.0
    ctl.update_pose(0.0, 0.0, 0.0, 0.6)
    assert ctl.step(0.6) == (0.0, 0.0, 0.0)  # last zone reading 0.55 s old
    ctl.update_zone(0.65, WALL_AHEAD, stale=True)
    assert ctl.step(0.66) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("stop", ["estop", "collision"])
def test_stops_preempt_a_guarded_goal(stop):
    ctl = guarded_controller()
    ctl.set_guarded_goal(Goal(-0.3, 0.0, 0.0), 0.15, 0.0)
    if stop == "estop":
        ctl.set_emergency(True)
    else:
        ctl.set_collision(True)
    assert ctl.state in (State.EMERGENCY_STOP, State.COLLISION_DETECTED)
    assert ctl.step(0.05) == (0.0, 0.0, 0.0) and ctl.goal is None
    with pytest.raises(GoalRejectedError):
        ctl.set_guarded_goal(Goal(-0.3, 0.0, 0.0), 0.15, 0.05)


def test_guarded_goal_rejections():
    ctl = guarded_controller()
    for goal, speed in ((Goal(float("nan"), 0.0, 0.0), 0.1), (Goal(0.1, 0.0, 0.0), 0.0),
                        (Goal(0.1, 0.0, 0.0), 0.5), (Goal(0.1, 0.0, 0.0), float("inf"))):
        with pytest.raises(GoalRejectedError):
            ctl.set_guarded_goal(goal, speed, 0.0)
    ctl.update_pose(0.0, 0.0, 0.0, 1.0)
    with pytest.raises(GoalRejectedError, match="zone"):
        ctl.set_guarded_goal(Goal(0.1, 0.0, 0.0), 0.1, 1.0)  # zone reading 1 s old
    fresh_pose_no_zone = PositionController()
    fresh_pose_no_zone.update_pose(0.0, 0.0, 0.0, 0.0)
    with pytest.raises(GoalRejectedError, match="zone"):
        fresh_pose_no_zone.set_guarded_goal(Goal(0.1, 0.0, 0.0), 0.1, 0.0)
    assert ctl.state == State.WAITING_FOR_POSE

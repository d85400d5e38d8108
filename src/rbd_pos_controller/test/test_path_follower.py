"""The path follower (FOLLOWING) on the kinematic robot: walks and turns at once, on-the-spot turns only
where the path has them, Table 2's saturations, stops preempt it (issue 27)."""

import math

import pytest

from rbd_geometry.goal import Goal
from rbd_pos_controller.closed_loop import run_goals, run_path
from rbd_pos_controller.control_law import Gains, wrap_angle
from rbd_pos_controller.controller import PositionController
from rbd_pos_controller.fsm import State
from rbd_pos_controller.goal import GoalRejectedError
from rbd_pos_controller.params import Params
from rbd_pos_controller.path_follower import FollowerParams, PathFollower

GAINS = Gains()  # Table 2
PARAMS = Params(gains=GAINS, max_v_hold=0.12)


def detour(step=0.2):
    """A detour like the planner's: turn on the spot, arc left, straight, arc right, corner, straight, turn."""
    poses = [(0.0, 0.0, 0.4)]  # on the spot
    x, y, th = 0.0, 0.0, 0.4
    for dth in [0.0, 0.0, -0.13, -0.13, -0.13, 0.0, 0.0, -0.13, 0.0]:
        kappa = dth / step
        if kappa == 0.0:
            x, y = x + step * math.cos(th), y + step * math.sin(th)
        else:
            x, y = x + (math.sin(th + dth) - math.sin(th)) / kappa, y + (math.cos(th) - math.cos(th + dth)) / kappa
        th += dth
        poses.append((x, y, th))
    poses.append((x, y, -0.6))  # a corner turned on the spot
    poses.append((x + 0.8 * math.cos(-0.6), y + 0.8 * math.sin(-0.6), -0.6))
    poses.append((poses[-1][0], poses[-1][1], 0.0))  # final heading
    return poses


def cross_track(p, path):
    """Distance from p to the polyline through the path's positions."""
    best = math.inf
    for a, b in zip(path, path[1:]):
        dx, dy = b[0] - a[0], b[1] - a[1]
        len2 = dx * dx + dy * dy
        u = 0.0 if len2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2))
        best = min(best, math.hypot(a[0] + u * dx - p[0], a[1] + u * dy - p[1]))
    return best


def test_detour_is_followed_closely_within_table2_saturations():
    path = detour()
    log = run_path(path, 0.3, PARAMS)
    end = log.poses[-1]
    assert math.hypot(end[1] - path[-1][0], end[2] - path[-1][1]) <= 0.03
    assert abs(wrap_angle(end[3] - path[-1][2])) <= 0.03
    full = [(0.0, 0.0)] + [p[:2] for p in path]
    assert max(cross_track(p[1:3], full) for p in log.poses) <= 0.05
    assert max(abs(c[1]) for c in log.cmds) <= 0.3 + 1e-9
    assert max(abs(c[2]) for c in log.cmds) <= 0.12 + 1e-9
    assert max(abs(c[3]) for c in log.cmds) <= GAINS.max_wz + 1e-9


def test_turns_while_walking_and_on_the_spot_only_at_the_paths_turns():
    path = detour()
    log = run_path(path, 0.3, PARAMS, latency=0.0)
    walking_turns = [c for c in log.cmds if c[1] > 0.1 and abs(c[3]) > 0.1]
    assert len(walking_turns) >= 10  # the arcs are walked, not pivoted
    spots = [(0.0, 0.0)] + [b[:2] for a, b in zip([(0.0, 0.0, 0.0)] + path, path) if a[:2] == b[:2]]
    poses = {round(p[0], 6): p for p in log.poses}
    for t, vx, _vy, wz in log.cmds:
        if abs(vx) < 0.02 and abs(wz) > 0.05:  # turning on the spot
            p = poses[round(t, 6)]
            assert min(math.hypot(p[1] - s[0], p[2] - s[1]) for s in spots) <= 0.06, (t, p)


def test_faster_than_pose_by_pose():
    path = detour()
    follow = run_path(path, 0.3, PARAMS)
    pose_by_pose = run_goals([Goal(x, y, yaw) for x, y, yaw in path], PARAMS)
    assert follow.done < 0.8 * pose_by_pose.done, (follow.done, pose_by_pose.done)


def test_a_slow_path_turns_slowly():
    log = run_path(detour(), 0.06, PARAMS)
    assert max(abs(c[1]) for c in log.cmds) <= 0.06 + 1e-9
    assert max(abs(c[3]) for c in log.cmds) <= GAINS.max_wz * 0.06 / 0.3 + 1e-9


def test_a_new_path_replaces_the_running_one_without_stopping():
    first = [(3.0, 0.0, 0.0)]
    second = [(2.0, 0.4, 0.2), (3.0, 0.6, 0.0)]
    seen = {}

    def replace(t, ctl, robot):
        if t >= 4.0 and "t" not in seen:
            seen["t"] = t
            ctl.set_path(second, 0.3, t)

    log = run_path(first, 0.3, PARAMS, on_step=replace)
    after = [c for c in log.cmds if seen["t"] <= c[0] <= seen["t"] + 1.0]
    assert min(c[1] for c in after) > 0.1  # kept walking
    assert math.hypot(log.poses[-1][1] - 3.0, log.poses[-1][2] - 0.6) <= 0.03


def test_slowdown_scale_applies():
    ctl = PositionController(PARAMS)
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    ctl.set_path([(2.0, 0.0, 0.0)], 0.3, 0.0)
    full = ctl.step(0.0)
    ctl.set_speed_scale(0.5)
    half = ctl.step(0.05)
    assert full[0] > 0.2 and abs(half[0] - 0.5 * full[0]) < 1e-9


@pytest.mark.parametrize("stop", ["estop", "collision"])
def test_stops_preempt_the_path_with_zero_velocity(stop):
    ctl = PositionController(PARAMS)
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    ctl.set_path([(2.0, 0.0, 0.0)], 0.3, 0.0)
    assert ctl.state == State.FOLLOWING and ctl.status == "running" and ctl.step(0.0)[0] > 0
    if stop == "estop":
        ctl.set_emergency(True)
    else:
        ctl.set_collision(True)
    assert ctl.step(0.05) == (0.0, 0.0, 0.0) and ctl.last_command == (0.0, 0.0, 0.0)
    assert ctl.follower is None
    with pytest.raises(GoalRejectedError):
        ctl.set_path([(2.0, 0.0, 0.0)], 0.3, 0.1)


@pytest.mark.parametrize(
    "path, speed",
    [
        ([], 0.2),
        ([(1.0, math.nan, 0.0)], 0.2),
        ([(1.0, 0.0, math.inf)], 0.2),
        ([(1.0, 0.0)], 0.2),
        ([(1.0, 0.0, 0.0)], 0.0),
        ([(1.0, 0.0, 0.0)], 0.31),
        ([(1.0, 0.0, 0.0)], math.nan),
    ],
)
def test_bad_paths_are_refused_without_motion(path, speed):
    ctl = PositionController(PARAMS)
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    with pytest.raises(GoalRejectedError):
        ctl.set_path(path, speed, 0.0)
    assert ctl.state == State.WAITING_FOR_POSE and ctl.step(0.0) == (0.0, 0.0, 0.0)


def test_stale_pose_stops_the_follower():
    ctl = PositionController(PARAMS)
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    ctl.set_path([(2.0, 0.0, 0.0)], 0.3, 0.0)
    assert ctl.step(0.1)[0] > 0
    assert ctl.step(1.0) == (0.0, 0.0, 0.0)  # pose 1 s old (pose_timeout 0.5 s)


def test_path_of_one_turn_and_a_path_already_done():
    log = run_path([(0.0, 0.0, 1.5)], 0.3, PARAMS)
    assert abs(log.poses[-1][3] - 1.5) <= 0.03 and max(math.hypot(p[1], p[2]) for p in log.poses) < 0.03
    follower = PathFollower([(0.0, 0.0, 0.0)], 0.3, GAINS, FollowerParams())
    assert follower.command((0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0) and follower.done


def test_a_turn_in_heading_bins_is_turned_through_without_slowing_at_each_bin():
    # Issue 27: the detour planner turns on the spot in 11.25 deg bins; the follower settled on each bin
    # (its yaw rate falling towards 0 every 11 deg), so a 45 deg turn took twice its time or more.
    bins = [(0.0, 0.0, math.radians(11.25 * i)) for i in range(1, 5)]
    binned = run_path(bins, 0.3, PARAMS)
    whole = run_path([bins[-1]], 0.3, PARAMS)
    assert abs(wrap_angle(binned.poses[-1][3] - math.radians(45.0))) <= 0.03
    assert binned.done <= whole.done + 0.1, (binned.done, whole.done)
    # One acceleration, one deceleration: the yaw rate never rises again at a bin.
    rates = [abs(c[3]) for c in binned.cmds]
    peak = rates.index(max(rates))
    assert all(b <= a + 1e-9 for a, b in zip(rates[peak:], rates[peak + 1:]))
    assert max(math.hypot(p[1], p[2]) for p in binned.poses) < 0.03


def test_a_turn_in_bins_goes_the_planned_way_round_past_half_a_turn():
    # 8 bins of -30 deg: 240 deg clockwise, the way the planner checked, not the 120 deg the other way.
    bins = [(0.0, 0.0, wrap_angle(math.radians(-30.0 * i))) for i in range(1, 9)]
    log = run_path(bins, 0.3, PARAMS)
    turned = sum(wrap_angle(b[3] - a[3]) for a, b in zip(log.poses, log.poses[1:]))
    assert turned == pytest.approx(math.radians(-240.0), abs=0.05), math.degrees(turned)

import math

import pytest

from rbd_geometry.goal import Goal
from rbd_pos_controller.control_law import Gains
from rbd_pos_controller.controller import PositionController
from rbd_pos_controller.fsm import MOTION_STATES, TRANSITIONS, Event, State
from rbd_pos_controller.goal import GoalRejectedError
from rbd_pos_controller.kinematic_sim import KinematicRobot
from rbd_pos_controller.params import Params


def controller_in(state, **params):
    """A controller at pose (0, 0, 0), driven into state through its public API."""
    ctl = PositionController(Params(**params))
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    if state == State.PRE_ROTATION:
        ctl.set_goal(Goal(0.0, 1.0, 0.0), 0.0)
    elif state == State.LINEAR:
        ctl.set_goal(Goal(0.2, 0.0, 0.0), 0.0)
    elif state == State.POST_ROTATION:
        ctl.set_goal(Goal(0.0, 0.0, 1.0), 0.0)
        ctl.step(0.0)
    elif state == State.BODY_POSE:
        ctl.set_goal(Goal(0.0, 0.0, 0.0, roll=0.2), 0.0)
        ctl.step(0.0)
    elif state == State.GUARDED:
        ctl.update_zone(0.0, [0, 0, 0, 0])
        ctl.set_guarded_goal(Goal(-0.3, 0.0, 0.0), 0.15, 0.0)
    elif state == State.FOLLOWING:
        ctl.set_path([(1.0, 0.0, 0.0)], 0.2, 0.0)
    elif state == State.EMERGENCY_STOP:
        ctl.set_emergency(True)
    elif state == State.COLLISION_DETECTED:
        ctl.set_collision(True)
    assert ctl.state == state
    return ctl


@pytest.mark.parametrize("state", list(State))
@pytest.mark.parametrize("event", list(Event))
def test_transition_table_is_what_fire_does(state, event):
    ctl = controller_in(state)
    accepted = ctl.fire(event)
    expected = TRANSITIONS.get((state, event))
    assert accepted == (expected is not None)
    assert ctl.state == (expected if expected is not None else state)


@pytest.mark.parametrize("state", [State.WAITING_FOR_POSE] + list(MOTION_STATES) + [State.COLLISION_DETECTED])
def test_estop_preempts_every_state_and_zeroes(state):
    ctl = controller_in(state)
    ctl.set_emergency(True)
    assert ctl.state == State.EMERGENCY_STOP and ctl.status == "emergency"
    assert ctl.step(0.05) == (0.0, 0.0, 0.0)
    assert ctl.goal is None
    ctl.set_emergency(False)
    if state == State.COLLISION_DETECTED:  # the collision is still reported
        assert ctl.state == State.COLLISION_DETECTED
    else:
        assert ctl.state == State.WAITING_FOR_POSE and ctl.status == "idle"


@pytest.mark.parametrize("state", [State.WAITING_FOR_POSE] + list(MOTION_STATES))
def test_collision_preempts_every_motion_state_and_clear_goes_idle(state):
    ctl = controller_in(state)
    ctl.set_collision(True)
    assert ctl.state == State.COLLISION_DETECTED and ctl.status == "collision"
    assert ctl.step(0.05) == (0.0, 0.0, 0.0)
    ctl.set_collision(False)
    assert ctl.state == State.WAITING_FOR_POSE


def test_release_estop_with_collision_still_active_goes_to_collision():
    ctl = controller_in(State.LINEAR)
    ctl.set_collision(True)
    ctl.set_emergency(True)
    ctl.set_emergency(False)
    assert ctl.state == State.COLLISION_DETECTED
    ctl.set_collision(False)
    assert ctl.state == State.WAITING_FOR_POSE


def test_collision_during_estop_keeps_estop():
    ctl = controller_in(State.EMERGENCY_STOP)
    ctl.set_collision(True)
    assert ctl.state == State.EMERGENCY_STOP
    ctl.set_collision(False)
    assert ctl.state == State.EMERGENCY_STOP


def test_pre_rotation_skipped_when_close():
    ctl = controller_in(State.WAITING_FOR_POSE)
    ctl.set_goal(Goal(0.0, 0.39, 0.0), 0.0)
    assert ctl.state == State.LINEAR
    ctl = controller_in(State.WAITING_FOR_POSE)
    ctl.set_goal(Goal(0.0, 0.41, 0.0), 0.0)
    assert ctl.state == State.PRE_ROTATION


def test_pre_rotation_turns_towards_goal_then_linear():
    ctl = controller_in(State.PRE_ROTATION, gains=Gains())
    vx, vy, wz = ctl.step(0.01)
    assert wz == pytest.approx(math.radians(36.0))  # gamma = +90 deg, saturated
    assert (vx, vy) == pytest.approx((0.0, 0.0))  # on the hold point
    ctl.update_pose(0.0, 0.0, math.pi / 2 - 0.01, 0.1)
    vx, vy, wz = ctl.step(0.1)
    assert ctl.state == State.LINEAR
    assert wz == 0.0 and vx == pytest.approx(0.3)


def test_goal_reached_skips_through_to_body_pose():
    ctl = controller_in(State.WAITING_FOR_POSE)
    ctl.set_goal(Goal(0.005, 0.0, 0.01, pitch=0.1), 0.0)
    assert ctl.step(0.0) == (0.0, 0.0, 0.0)
    assert ctl.state == State.BODY_POSE
    assert ctl.body_pose_request.pitch == pytest.approx(0.1)
    ctl.body_pose_done(0.1)
    ctl.step(0.1)
    assert ctl.state == State.WAITING_FOR_POSE and ctl.status == "idle"
    assert [h[1] for h in ctl.history] == [Event.GOAL_NEAR, Event.REACHED, Event.ORIENTED, Event.BODY_POSE_DONE]


def test_body_pose_waits_for_answer_and_settle_time():
    ctl = controller_in(State.BODY_POSE, body_pose_settle=0.5)
    ctl.step(1.0)
    assert ctl.state == State.BODY_POSE  # no answer yet
    ctl.body_pose_done(1.0)
    ctl.step(1.2)
    assert ctl.state == State.BODY_POSE  # settling
    ctl.step(1.6)
    assert ctl.state == State.WAITING_FOR_POSE


@pytest.mark.parametrize(
    "goal",
    [
        Goal(float("nan"), 0.0, 0.0),
        Goal(0.0, float("inf"), 0.0),
        Goal(0.0, 0.0, float("nan")),
        Goal(0.0, 0.0, 0.0, roll=float("nan")),
        Goal(0.0, 0.0, 0.0, body_height=float("nan")),
    ],
)
def test_nan_goal_rejected_no_motion(goal):
    ctl = controller_in(State.WAITING_FOR_POSE)
    with pytest.raises(GoalRejectedError, match="non-finite"):
        ctl.set_goal(goal, 0.0)
    assert ctl.state == State.WAITING_FOR_POSE
    assert ctl.step(0.1) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("state", [State.EMERGENCY_STOP, State.COLLISION_DETECTED])
def test_goal_rejected_while_stopped(state):
    ctl = controller_in(state)
    with pytest.raises(GoalRejectedError):
        ctl.set_goal(Goal(1.0, 0.0, 0.0), 0.0)
    assert ctl.state == state


def test_goal_rejected_without_fresh_pose():
    ctl = PositionController()
    with pytest.raises(GoalRejectedError, match="pose"):
        ctl.set_goal(Goal(1.0, 0.0, 0.0), 0.0)
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    with pytest.raises(GoalRejectedError, match="pose"):
        ctl.set_goal(Goal(1.0, 0.0, 0.0), 0.6)


def test_nan_pose_ignored():
    ctl = PositionController()
    assert not ctl.update_pose(float("nan"), 0.0, 0.0, 0.0)
    assert not ctl.pose_fresh(0.0)


def test_stale_pose_zeroes_velocity_then_resumes():
    ctl = controller_in(State.LINEAR)
    assert ctl.step(0.4)[0] > 0.0
    assert ctl.step(0.51) == (0.0, 0.0, 0.0)
    assert ctl.state == State.LINEAR  # goal kept
    ctl.update_pose(0.0, 0.0, 0.0, 0.6)
    assert ctl.step(0.6)[0] > 0.0


@pytest.mark.parametrize("scale, factor", [(0.5, 0.5), (0.0, 0.0), (2.0, 1.0), (-1.0, 0.0), (float("nan"), 0.0)])
def test_speed_scale(scale, factor):
    ctl = controller_in(State.LINEAR)
    full = ctl.step(0.0)[0]
    ctl.set_speed_scale(scale)
    assert ctl.step(0.0)[0] == pytest.approx(full * factor)


def test_new_goal_replaces_running_goal():
    ctl = controller_in(State.LINEAR)
    ctl.set_goal(Goal(0.0, -2.0, 0.0), 0.0)
    assert ctl.state == State.PRE_ROTATION
    assert ctl.step(0.0)[2] < 0.0


# ---------------------------------------------------------------- closed loop


def simulate(goals, params, drift=0.0, latency=0.08, rate=10.0, limit=120.0):
    """Run goals on the kinematic robot; return (time, max deviation from the segments, robot, trace)."""
    robot = KinematicRobot(latency=latency, drift_per_rad=drift)
    ctl = PositionController(params)
    dt, t, next_ctl = 0.005, 0.0, 0.0
    start = (0.0, 0.0)
    max_dev = 0.0
    for goal in goals:
        ctl.update_pose(robot.x, robot.y, robot.yaw, t)
        ctl.set_goal(goal, t)
        a, b = start, (goal.x, goal.y)
        while ctl.state != State.WAITING_FOR_POSE:
            if t >= next_ctl - 1e-9:
                ctl.update_pose(robot.x, robot.y, robot.yaw, t)
                if ctl.body_pose_request is not None:
                    ctl.body_pose_done(t)
                robot.command(*ctl.step(t))
                next_ctl += 1.0 / rate
            robot.advance(dt)
            t += dt
            max_dev = max(max_dev, segment_distance((robot.x, robot.y), a, b))
            assert t < limit, "did not finish"
        start = b
    return t, max_dev, robot


def segment_distance(p, a, b):
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    u = 0.0 if length2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))
    return math.hypot(p[0] - a[0] - u * dx, p[1] - a[1] - u * dy)


THESIS_PATH = [Goal(1.0, 0.0, 0.0), Goal(-1.0, 0.0, math.pi), Goal(0.0, 0.0, 0.0)]
DRIFT = 0.2  # m per rad turned, sideways: 0.4 m over a 180 deg turn


def test_thesis_path_with_default_params():
    t, dev, robot = simulate(THESIS_PATH, Params(gains=Gains(k_x=3.0, k_y=3.0, k_alpha=3.0)), drift=DRIFT)
    assert math.hypot(robot.x, robot.y) <= 0.03
    assert abs(math.degrees(robot.yaw)) <= 2.0
    assert dev <= 0.05
    assert t <= 26.0


def test_table2_gains_are_slower():
    t, _, robot = simulate(THESIS_PATH, Params(gains=Gains()), drift=0.0)
    assert math.hypot(robot.x, robot.y) <= 0.03
    assert t > 26.0


def test_position_control_during_rotation_halves_drift():
    spin = [Goal(0.0, 0.0, math.pi - 1e-3)]
    _, _, without = simulate(spin, Params(rotation_x_control=False, rotation_y_control=False), drift=DRIFT)
    _, _, with_y = simulate(spin, Params(rotation_x_control=False, rotation_y_control=True), drift=DRIFT)
    drift_without = math.hypot(without.x, without.y)
    drift_with = math.hypot(with_y.x, with_y.y)
    assert drift_without > 0.3
    assert drift_with * 2.0 <= drift_without


def test_on_enter_hook_sees_every_state_change():
    seen = []
    ctl = PositionController(on_enter=seen.append)
    ctl.update_pose(0.0, 0.0, 0.0, 0.0)
    ctl.set_goal(Goal(1.0, 0.0, 0.0), 0.0)
    ctl.set_emergency(True)
    assert seen == [State.PRE_ROTATION, State.EMERGENCY_STOP]

"""Closed-loop runs of the controller on the kinematic robot, recorded as a RunLog. ROS-free."""

import math
from typing import Callable, Optional, Sequence

from rbd_geometry.goal import Goal
from rbd_pos_controller.controller import PositionController
from rbd_pos_controller.fsm import State
from rbd_pos_controller.kinematic_sim import KinematicRobot
from rbd_pos_controller.params import Params
from rbd_pos_controller.runlog import RunLog

#: Gives the controller its next goal or path at time t (and records it in the log).
SetTarget = Callable[[PositionController, RunLog, float], None]
#: Called before each control step with (t, controller, robot) (tests inject events there).
OnStep = Callable[[float, PositionController, KinematicRobot], None]


def run_goals(
    goals: Sequence[Goal],
    params: Optional[Params] = None,
    drift_per_rad: float = 0.0,
    drift_heading: float = math.pi / 2,
    latency: float = 0.08,
    rate: float = 20.0,
    pose_rate: float = 20.0,
    dt: float = 0.005,
    limit: float = 120.0,
    label: str = "",
) -> RunLog:
    """Drive the kinematic robot from the origin through goals; return the recorded run.

    Raises:
        RuntimeError: if the goals are not all reached within limit seconds.
    """
    robot = KinematicRobot(latency=latency, drift_per_rad=drift_per_rad, drift_heading=drift_heading)
    log = RunLog((0.0, 0.0, 0.0))
    log.label = label

    def go_to(goal: Goal) -> SetTarget:
        def set_target(ctl: PositionController, log: RunLog, t: float) -> None:
            log.goals.append((t, goal.x, goal.y, goal.yaw))
            ctl.set_goal(goal, t)

        return set_target

    return simulate(robot, PositionController(params), log, [go_to(g) for g in goals], rate, pose_rate, dt, limit,
                    what="goals not reached")


def run_path(
    poses: Sequence[Sequence[float]],
    max_speed: float,
    params: Optional[Params] = None,
    start: Sequence[float] = (0.0, 0.0, 0.0),
    latency: float = 0.08,
    rate: float = 20.0,
    dt: float = 0.005,
    limit: float = 120.0,
    on_step: Optional[OnStep] = None,
) -> RunLog:
    """Follow a path of poses (FOLLOWING) with the kinematic robot from start; return the recorded run.

    ``on_step(t, controller, robot)`` is called before each control step (tests inject events there).

    Raises:
        RuntimeError: if the path is not done within limit seconds.
    """
    robot = KinematicRobot(x=start[0], y=start[1], yaw=start[2], latency=latency)

    def set_target(ctl: PositionController, log: RunLog, t: float) -> None:
        last = poses[-1]
        log.goals.append((t, last[0], last[1], last[2]))
        ctl.set_path(poses, max_speed, t)

    return simulate(robot, PositionController(params), RunLog(tuple(start)), [set_target], rate, rate, dt, limit,
                    on_step, what="path not done")


def simulate(
    robot: KinematicRobot,
    ctl: PositionController,
    log: RunLog,
    targets: Sequence[SetTarget],
    rate: float,
    pose_rate: float,
    dt: float,
    limit: float,
    on_step: Optional[OnStep] = None,
    what: str = "not done",
) -> RunLog:
    """The closed loop: each target in turn, run until the controller is back in WAITING_FOR_POSE.

    Time advances in steps of dt; the robot's pose reaches the controller at pose_rate, the
    controller steps at rate (a body pose request is answered at once), and poses, commands and
    targets are recorded in log.

    Raises:
        RuntimeError: "<what> within <limit> s" when the simulated time passes limit.
    """
    t, next_ctl, next_pose = 0.0, 0.0, 0.0
    for set_target in targets:
        ctl.update_pose(robot.x, robot.y, robot.yaw, t)
        set_target(ctl, log, t)
        while ctl.state != State.WAITING_FOR_POSE:
            if t >= next_pose - 1e-9:
                ctl.update_pose(robot.x, robot.y, robot.yaw, t)
                log.poses.append((t, robot.x, robot.y, robot.yaw))
                next_pose += 1.0 / pose_rate
            if t >= next_ctl - 1e-9:
                if on_step is not None:
                    on_step(t, ctl, robot)
                if ctl.body_pose_request is not None:
                    ctl.body_pose_done(t)
                cmd = ctl.step(t)
                robot.command(*cmd)
                log.cmds.append((t,) + tuple(cmd))
                next_ctl += 1.0 / rate
            robot.advance(dt)
            t += dt
            if t > limit:
                raise RuntimeError("%s within %.0f s (state %s)" % (what, limit, ctl.state.value))
    log.done = t
    log.poses.append((t, robot.x, robot.y, robot.yaw))
    return log


THESIS_PATH = (Goal(1.0, 0.0, 0.0), Goal(-1.0, 0.0, math.pi), Goal(0.0, 0.0, 0.0))
ROTATION_180 = (Goal(0.0, 0.0, math.pi - 1e-3),)

"""The position controller's states, events and transition table (thesis Fig. 9). ROS-free.

Transitions are one explicit table: a new goal is accepted when idle and replaces the current
one while moving; e-stop and collision preempt every motion state (the controller zeroes the
velocity on entry).

GUARDED is the avoidance motion (issue 17: escape, dodge): a straight translation to a
position without turning, capped at a low speed, gated per side by the LiDAR zone
(:mod:`rbd_pos_controller.zone_guard`) instead of the slowdown scale, because it starts with
something in the zone.

FOLLOWING follows a path of poses (issue 27: the detour), walking and turning at once
(:mod:`rbd_pos_controller.path_follower`); a new path (or goal) replaces it without stopping.

:data:`STATUS` maps each state to its word on ``/rbd_pos_controller/status``
(rbd_msgs/PosControllerStatus).
"""

import enum

from rbd_msgs.msg import PosControllerStatus as Status


class State(enum.Enum):
    """States of the position controller."""

    WAITING_FOR_POSE = "WAITING_FOR_POSE"
    PRE_ROTATION = "PRE_ROTATION"
    LINEAR = "LINEAR"
    POST_ROTATION = "POST_ROTATION"
    BODY_POSE = "BODY_POSE"
    GUARDED = "GUARDED"  # avoidance translation, gated per side by the zone
    FOLLOWING = "FOLLOWING"  # following a path of poses (detour)
    EMERGENCY_STOP = "EMERGENCY_STOP"
    COLLISION_DETECTED = "COLLISION_DETECTED"


class Event(enum.Enum):
    """Events that move the position controller FSM."""

    GOAL_FAR = "GOAL_FAR"  # new goal, rho >= skip distance: turn towards it first
    GOAL_NEAR = "GOAL_NEAR"  # new goal, rho < skip distance: no pre-rotation
    GOAL_GUARDED = "GOAL_GUARDED"  # new avoidance goal (translation only, zone-gated)
    GUARDED_REACHED = "GUARDED_REACHED"  # the avoidance goal's position is reached (no rotation follows)
    GOAL_PATH = "GOAL_PATH"  # new path to follow
    PATH_DONE = "PATH_DONE"  # the path's last pose, heading included, is reached
    ALIGNED = "ALIGNED"  # |gamma| within tolerance
    REACHED = "REACHED"  # rho within tolerance
    ORIENTED = "ORIENTED"  # |delta| within tolerance
    BODY_POSE_DONE = "BODY_POSE_DONE"  # set_body_pose answered (or failed) and settled
    ESTOP = "ESTOP"
    ESTOP_RELEASE = "ESTOP_RELEASE"
    COLLISION = "COLLISION"
    COLLISION_CLEAR = "COLLISION_CLEAR"


MOTION_STATES = (State.PRE_ROTATION, State.LINEAR, State.POST_ROTATION, State.BODY_POSE, State.GUARDED,
                 State.FOLLOWING)
STOP_STATES = (State.EMERGENCY_STOP, State.COLLISION_DETECTED)

TRANSITIONS = {}  # type: Dict[Tuple[State, Event], State]
TRANSITIONS.update(
    {
        (State.PRE_ROTATION, Event.ALIGNED): State.LINEAR,
        (State.LINEAR, Event.REACHED): State.POST_ROTATION,
        (State.POST_ROTATION, Event.ORIENTED): State.BODY_POSE,
        (State.BODY_POSE, Event.BODY_POSE_DONE): State.WAITING_FOR_POSE,
        (State.GUARDED, Event.GUARDED_REACHED): State.WAITING_FOR_POSE,
        (State.FOLLOWING, Event.PATH_DONE): State.WAITING_FOR_POSE,
        (State.EMERGENCY_STOP, Event.ESTOP_RELEASE): State.WAITING_FOR_POSE,
        (State.COLLISION_DETECTED, Event.COLLISION_CLEAR): State.WAITING_FOR_POSE,
        (State.COLLISION_DETECTED, Event.ESTOP): State.EMERGENCY_STOP,
        # A collision while the e-stop is engaged keeps the e-stop (it needs explicit release).
        (State.EMERGENCY_STOP, Event.COLLISION): State.EMERGENCY_STOP,
    }
)
for _state in (State.WAITING_FOR_POSE,) + MOTION_STATES:
    # A new goal is accepted when idle and replaces the current one while moving.
    TRANSITIONS[(_state, Event.GOAL_FAR)] = State.PRE_ROTATION
    TRANSITIONS[(_state, Event.GOAL_NEAR)] = State.LINEAR
    TRANSITIONS[(_state, Event.GOAL_GUARDED)] = State.GUARDED
    TRANSITIONS[(_state, Event.GOAL_PATH)] = State.FOLLOWING
    TRANSITIONS[(_state, Event.ESTOP)] = State.EMERGENCY_STOP
    TRANSITIONS[(_state, Event.COLLISION)] = State.COLLISION_DETECTED

STATUS = {
    State.WAITING_FOR_POSE: Status.IDLE,
    State.PRE_ROTATION: Status.RUNNING,
    State.LINEAR: Status.RUNNING,
    State.POST_ROTATION: Status.RUNNING,
    State.BODY_POSE: Status.RUNNING,
    State.GUARDED: Status.RUNNING,
    State.FOLLOWING: Status.RUNNING,
    State.EMERGENCY_STOP: Status.EMERGENCY,
    State.COLLISION_DETECTED: Status.COLLISION,
}

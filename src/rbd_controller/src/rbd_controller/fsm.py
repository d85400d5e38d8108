"""Main controller state machine (thesis Fig. 6) as an explicit transition table. ROS-free.

EMERGENCY_STOP and COLLISION_DETECTED are accepted from every state; the state that was
interrupted is kept in a resume slot and restored when the stop is released/cleared. The
e-stop needs an explicit release; a collision clears by itself. A collision reported while
the e-stop is engaged is remembered and takes over when the e-stop is released.

OPERATOR_LOST is the operator-link watchdog's stop (the laptop's heartbeat is gone): entered
from the work states on OPERATOR_LOST (the core decides when, per policy), left on
OPERATOR_BACK (heartbeats again) or ESTOP_RELEASE (an explicit release acknowledges the loss).
It never gates the e-stop: ESTOP preempts it like any other state.

Active collision avoidance (issue 17) adds four states, all entered and left through the table:

- BLOCKED: a stop state like COLLISION_DETECTED, entered from it when the blocking points are
  classified static (BLOCKED_STATIC) while a trick was interrupted; a moving blocker sends it
  back (OBSTACLE_MOVING: people are waited for, as in the thesis), a clear zone resumes, and
  AVOID (after ~blocked_timeout, avoidance enabled) starts ESCAPING.
- ESCAPING: a guarded translation away from the blocking side until the zone is clear by a
  margin (ESCAPED -> AVOIDING). It starts with the obstacle inside the zone, so the collision
  flag does not preempt it: the position controller gates the motion per side on the zone.
- AVOIDING: the planned detour, pose by pose, under the normal collision rules
  (COLLISION -> COLLISION_DETECTED), then EXECUTING continues the trick (DETOUR_DONE).
- DODGING: an idle robot steps away from an approaching visitor and back home (guarded, like
  ESCAPING); DODGE_DONE returns to WAITING_FOR_GESTURE.

GIVE_UP (no detour, too long, ~avoid_timeout) returns to EXECUTING with the blocked pose
dropped (the core decides skip or home). E-stop, operator loss and a stale zone (ZONE_STALE)
preempt every avoidance state as they preempt tricks; the avoidance states are resumable like
the work states.
"""

import enum
from typing import Callable, Dict, Optional


class State(enum.Enum):
    """Main controller states; values match rbd_msgs/ControllerState constants."""

    EMERGENCY_STOP = 0
    WAITING_FOR_GESTURE = 1
    GENERATING_PATH = 2
    EXECUTING = 3
    COLLISION_DETECTED = 4
    OPERATOR_LOST = 5
    BLOCKED = 6
    ESCAPING = 7
    AVOIDING = 8
    DODGING = 9


class Event(enum.Enum):
    """Events of the main controller."""

    ESTOP = "ESTOP"
    ESTOP_RELEASE = "ESTOP_RELEASE"
    COLLISION = "COLLISION"
    COLLISION_CLEAR = "COLLISION_CLEAR"
    GESTURE = "GESTURE"  # a known gesture arrived
    PATH_READY = "PATH_READY"  # GeneratePath returned poses
    PATH_FAILED = "PATH_FAILED"  # unknown command / navigation unavailable / no pose
    QUEUE_EMPTY = "QUEUE_EMPTY"  # last pose reached
    ABORT = "ABORT"  # the position controller refused a pose or timed out
    OPERATOR_LOST = "OPERATOR_LOST"  # operator heartbeat lost (watchdog, per policy)
    OPERATOR_BACK = "OPERATOR_BACK"  # operator heartbeat back
    BLOCKED_STATIC = "BLOCKED_STATIC"  # the blocking points are static (map or unmoved for ~static_after)
    OBSTACLE_MOVING = "OBSTACLE_MOVING"  # the blocking points move (a person): wait as the thesis robot
    AVOID = "AVOID"  # blocked for ~blocked_timeout with avoidance on
    ESCAPED = "ESCAPED"  # the zone is clear by the escape margin
    DETOUR_DONE = "DETOUR_DONE"  # the last detour pose is reached
    GIVE_UP = "GIVE_UP"  # no detour / too long / ~avoid_timeout: the blocked pose is dropped
    DODGE = "DODGE"  # a visitor approaches the idle robot
    DODGE_DONE = "DODGE_DONE"  # back home after a dodge
    ZONE_STALE = "ZONE_STALE"  # the zone reports stale/invalid data or is silent: stop


#: Target meaning "the state stored in the resume slot".
RESUME = "RESUME"

STOP_STATES = (State.EMERGENCY_STOP, State.COLLISION_DETECTED, State.OPERATOR_LOST, State.BLOCKED)
TRICK_STATES = (State.WAITING_FOR_GESTURE, State.GENERATING_PATH, State.EXECUTING)
AVOID_STATES = (State.ESCAPING, State.AVOIDING, State.DODGING)
WORK_STATES = TRICK_STATES + AVOID_STATES
#: States whose motion is guarded per side by the position controller, not held by the collision flag.
GUARDED_STATES = (State.ESCAPING, State.DODGING)

TRANSITIONS = {
    (State.WAITING_FOR_GESTURE, Event.GESTURE): State.GENERATING_PATH,
    (State.GENERATING_PATH, Event.PATH_READY): State.EXECUTING,
    (State.GENERATING_PATH, Event.PATH_FAILED): State.WAITING_FOR_GESTURE,
    (State.EXECUTING, Event.QUEUE_EMPTY): State.WAITING_FOR_GESTURE,
    (State.EXECUTING, Event.ABORT): State.WAITING_FOR_GESTURE,
    (State.EMERGENCY_STOP, Event.ESTOP_RELEASE): RESUME,
    (State.COLLISION_DETECTED, Event.COLLISION_CLEAR): RESUME,
    (State.COLLISION_DETECTED, Event.ESTOP): State.EMERGENCY_STOP,
    (State.EMERGENCY_STOP, Event.COLLISION): State.EMERGENCY_STOP,
    (State.EMERGENCY_STOP, Event.OPERATOR_LOST): State.EMERGENCY_STOP,
    (State.COLLISION_DETECTED, Event.OPERATOR_LOST): State.COLLISION_DETECTED,
    (State.OPERATOR_LOST, Event.OPERATOR_BACK): RESUME,
    (State.OPERATOR_LOST, Event.ESTOP_RELEASE): RESUME,
    (State.OPERATOR_LOST, Event.ESTOP): State.EMERGENCY_STOP,
    (State.OPERATOR_LOST, Event.COLLISION): State.OPERATOR_LOST,
    # issue 17: avoidance
    (State.COLLISION_DETECTED, Event.BLOCKED_STATIC): State.BLOCKED,
    (State.COLLISION_DETECTED, Event.DODGE): State.DODGING,
    (State.BLOCKED, Event.OBSTACLE_MOVING): State.COLLISION_DETECTED,
    (State.BLOCKED, Event.COLLISION_CLEAR): RESUME,
    (State.BLOCKED, Event.COLLISION): State.BLOCKED,
    (State.BLOCKED, Event.ESTOP): State.EMERGENCY_STOP,
    (State.BLOCKED, Event.OPERATOR_LOST): State.BLOCKED,
    (State.BLOCKED, Event.AVOID): State.ESCAPING,
    (State.BLOCKED, Event.GIVE_UP): State.EXECUTING,
    (State.ESCAPING, Event.ESCAPED): State.AVOIDING,
    (State.ESCAPING, Event.GIVE_UP): State.EXECUTING,
    (State.ESCAPING, Event.OBSTACLE_MOVING): State.COLLISION_DETECTED,
    (State.AVOIDING, Event.DETOUR_DONE): State.EXECUTING,
    (State.AVOIDING, Event.GIVE_UP): State.EXECUTING,
    (State.WAITING_FOR_GESTURE, Event.DODGE): State.DODGING,
    (State.DODGING, Event.DODGE_DONE): State.WAITING_FOR_GESTURE,
}  # type: Dict[Tuple[State, Event], object]
for _state in WORK_STATES:
    TRANSITIONS[(_state, Event.ESTOP)] = State.EMERGENCY_STOP
    TRANSITIONS[(_state, Event.COLLISION)] = State.COLLISION_DETECTED
    TRANSITIONS[(_state, Event.OPERATOR_LOST)] = State.OPERATOR_LOST
    TRANSITIONS[(_state, Event.ZONE_STALE)] = State.COLLISION_DETECTED
for _state in GUARDED_STATES:
    # Guarded motions start with something in the zone: the collision flag is only tracked; the
    # position controller gates every command on the zone side it heads to.
    TRANSITIONS[(_state, Event.COLLISION)] = _state


class Fsm:
    """Table-driven FSM with a resume slot and on_enter hooks.

    Args:
        on_enter: state -> callback(previous_state) run after entering the state.
        initial: start state (power-up is EMERGENCY_STOP, DESIGN §5.1).
    """

    def __init__(
        self,
        on_enter: Optional[Dict[State, Callable[[State], None]]] = None,
        initial: State = State.EMERGENCY_STOP,
    ) -> None:
        self.state = initial
        self.resume = State.WAITING_FOR_GESTURE
        self.estop = initial == State.EMERGENCY_STOP
        self.collision = False
        self.operator_lost = False
        self.epoch = 0
        self.on_enter = dict(on_enter or {})
        self.history = []  # type: List[Tuple[State, Event, State]]

    def fire(self, event: Event) -> bool:
        """Apply event; return True if the state changed or the event was accepted.

        Stop flags are tracked even when the table has no entry (e.g. a collision clearing
        while the e-stop is engaged).
        """
        if event == Event.ESTOP:
            self.estop = True
        elif event == Event.ESTOP_RELEASE:
            self.estop = False
        elif event == Event.COLLISION:
            self.collision = True
        elif event == Event.COLLISION_CLEAR:
            self.collision = False
        elif event == Event.OPERATOR_LOST:
            self.operator_lost = True
        elif event == Event.OPERATOR_BACK:
            self.operator_lost = False
        if event == Event.ESTOP_RELEASE:
            self.operator_lost = False  # an explicit release acknowledges a lost operator link
        target = TRANSITIONS.get((self.state, event))
        if target is None:
            return False
        source = self.state
        if target == RESUME:
            target = self.resume
            if source != State.COLLISION_DETECTED and self.collision:
                target = State.COLLISION_DETECTED
            elif source in (State.COLLISION_DETECTED, State.BLOCKED) and self.operator_lost:
                target = State.OPERATOR_LOST
        if self.collision and target in WORK_STATES and target not in GUARDED_STATES and source not in TRICK_STATES:
            # Leaving a stop or a guarded motion for a trick-like state while the zone still
            # reports a collision (e.g. GIVE_UP while BLOCKED): stop first, go on when it clears.
            self.resume = target
            target = State.COLLISION_DETECTED
        elif target in STOP_STATES and source in WORK_STATES:
            self.resume = source
        if target == source:
            return True
        self.state = target
        self.epoch += 1
        self.history.append((source, event, target))
        hook = self.on_enter.get(target)
        if hook is not None:
            hook(source)
        return True

"""Main controller state machine (thesis Fig. 6) as an explicit transition table. ROS-free.

EMERGENCY_STOP and COLLISION_DETECTED are accepted from every state; the state that was
interrupted is kept in a resume slot and restored when the stop is released/cleared. The
e-stop needs an explicit release; a collision clears by itself. A collision reported while
the e-stop is engaged is remembered and takes over when the e-stop is released.

OPERATOR_LOST is the operator-link watchdog's stop (the laptop's heartbeat is gone): entered
from the work states on OPERATOR_LOST (the core decides when, per policy), left on
OPERATOR_BACK (heartbeats again) or ESTOP_RELEASE (an explicit release acknowledges the loss).
It never gates the e-stop: ESTOP preempts it like any other state.
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
    OPERATOR_LOST = 5  # not yet a constant in rbd_msgs/ControllerState (requested)


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


#: Target meaning "the state stored in the resume slot".
RESUME = "RESUME"

STOP_STATES = (State.EMERGENCY_STOP, State.COLLISION_DETECTED, State.OPERATOR_LOST)
WORK_STATES = (State.WAITING_FOR_GESTURE, State.GENERATING_PATH, State.EXECUTING)

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
}  # type: Dict[Tuple[State, Event], object]
for _state in WORK_STATES:
    TRANSITIONS[(_state, Event.ESTOP)] = State.EMERGENCY_STOP
    TRANSITIONS[(_state, Event.COLLISION)] = State.COLLISION_DETECTED
    TRANSITIONS[(_state, Event.OPERATOR_LOST)] = State.OPERATOR_LOST


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
            elif source == State.COLLISION_DETECTED and self.operator_lost:
                target = State.OPERATOR_LOST
        if target in STOP_STATES and source in WORK_STATES:
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

"""Controller states the avoidance tests start from, reached through the FSM's own events."""

from rbd_controller.core import MainController
from rbd_controller.fsm import Event, State


def avoiding(ctl: MainController):
    """An executing trick, blocked by a static obstacle and escaped: AVOIDING towards the pose (2, 0).

    Returns:
        The controller's avoidance behaviour.
    """
    ctl.set_emergency(False)
    ctl.fsm.fire(Event.GESTURE)
    ctl.fsm.fire(Event.PATH_READY)
    ctl.tricks.current = ((2.0, 0.0, 0.0), "blocked pose")
    for event in (Event.COLLISION, Event.BLOCKED_STATIC, Event.AVOID, Event.COLLISION_CLEAR, Event.ESCAPED):
        ctl.fsm.fire(event)
    assert ctl.state == State.AVOIDING
    return ctl.avoidance

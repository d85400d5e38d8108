"""When to show the nominal standing pose instead of the robot's own joint angles (no ROS).

The A1 driver publishes ``/joint_states`` from the motor angles of SDK 3.3.3/3.3.4's HighState;
the v3.3/v3.3.1 layout has none. Without joint states robot_state_publisher publishes no leg
TFs and RViz shows the legs in error, so a fallback publishes a nominal standing pose, but
only while nobody else does: the first message of another publisher silences it at once.
"""

from typing import Optional, Tuple

#: diagnostic_msgs/DiagnosticStatus levels.
OK = 0
WARN = 1


class JointStateWatch:
    """Tracks the joint states of other publishers and decides whether the fallback speaks.

    Args:
        timeout: the fallback publishes when no other publisher's joint state arrived for this
            long [s] (also at start-up, from the time of construction).
        now: the current time [s] (any monotonic clock).

    Raises:
        ValueError: if timeout is not > 0.
    """

    def __init__(self, timeout: float, now: float) -> None:
        if not timeout > 0.0:
            raise ValueError("timeout must be > 0, got %r" % (timeout,))
        self.timeout = timeout
        self.start = now
        self.last: Optional[float] = None
        self.source = ""
        self.received = 0

    def on_message(self, sender: str, now: float, own: str) -> None:
        """A joint state arrived from node ``sender``; messages of ``own`` (the fallback) are ignored."""
        if sender == own:
            return
        self.last = now
        self.source = sender
        self.received += 1

    def silent_for(self, now: float) -> float:
        """Seconds since the last joint state of another publisher (or since start)."""
        return now - (self.last if self.last is not None else self.start)

    def should_publish(self, now: float) -> bool:
        """True while the robot's own joint states are missing or stale."""
        return self.silent_for(now) >= self.timeout

    def status(self, now: float) -> Tuple[int, str]:
        """Diagnostic level and message for the current situation."""
        if not self.should_publish(now):
            return OK, "joint angles from %s" % self.source
        if self.last is None:
            return WARN, ("no /joint_states from the robot: legs show the nominal standing pose "
                          "(SDK v3.3/v3.3.1 HighState has no motor angles; 3.3.3/3.3.4 has)")
        return WARN, ("no /joint_states from %s for %.1f s: legs show the nominal standing pose"
                      % (self.source, self.silent_for(now)))

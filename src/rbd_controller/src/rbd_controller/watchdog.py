"""Operator-link watchdog: the laptop app's heartbeat stopped arriving. ROS-free.

The watchdog arms with the first heartbeat (a robot run without the laptop app is not
stopped by it) and reports the link lost once no heartbeat came for ``timeout`` seconds.
``disarm()`` forgets the link until the next heartbeat (an explicit release acknowledges
the loss).
"""


POLICIES = ("stop", "finish")


class OperatorWatchdog:
    """Heartbeat timeout detector.

    Args:
        timeout: heartbeat silence that counts as a lost link [s]; <= 0 disables the watchdog.

    Raises:
        ValueError: timeout is not a finite number.
    """

    def __init__(self, timeout: float) -> None:
        timeout = float(timeout)
        if timeout != timeout or timeout in (float("inf"), float("-inf")):
            raise ValueError("operator_timeout must be a finite number, got %r" % timeout)
        self.timeout = timeout
        self.last = None  # type: Optional[float]

    @property
    def enabled(self) -> bool:
        """True when a positive timeout is configured."""
        return self.timeout > 0.0

    @property
    def armed(self) -> bool:
        """True once a heartbeat has been seen (and not disarmed since)."""
        return self.last is not None

    def beat(self, now: float) -> None:
        """Record a heartbeat received at ``now`` [s]."""
        if self.last is None or now >= self.last:
            self.last = now

    def disarm(self) -> None:
        """Forget the link until the next heartbeat."""
        self.last = None

    def lost(self, now: float) -> bool:
        """True when enabled, armed and the last heartbeat is older than the timeout."""
        return self.enabled and self.last is not None and now - self.last > self.timeout

"""Operator GUI (CustomTkinter). Talks to the robot only through a backend object it is given."""

import queue
from typing import Any, Iterator, Tuple


def drain(events: "queue.Queue") -> Iterator[Tuple[str, Any]]:
    """Every ``(kind, value)`` queued so far, without blocking (for a Tk poll)."""
    while True:
        try:
            yield events.get_nowait()
        except queue.Empty:
            return

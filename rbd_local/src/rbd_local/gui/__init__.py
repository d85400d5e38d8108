"""Operator GUI (CustomTkinter). Talks to the robot only through a backend object it is given."""

import queue
import threading
from typing import Any, Callable, Iterator, Tuple


def drain(events: "queue.Queue") -> Iterator[Tuple[str, Any]]:
    """Every ``(kind, value)`` queued so far, without blocking (for a Tk poll)."""
    while True:
        try:
            yield events.get_nowait()
        except queue.Empty:
            return


def in_background(events: "queue.Queue", kind: str, call: Callable[[], Any], failed: str, name: str) -> None:
    """Run ``call()`` in a daemon thread and queue ``(kind, its result)`` for the Tk thread.

    A panel must always give an answer: when the call raises, the queued value is the text
    ``"<failed>: <error>"`` instead (a ConnectionError / ValueError by its message, anything
    else by its repr).

    Args:
        events: the panel's event queue (read on the Tk thread with :func:`drain`).
        kind: the event's kind.
        call: the blocking call (a robot request).
        failed: the beginning of the error text, e.g. ``"preflight failed"``.
        name: the thread's name.
    """

    def work() -> None:
        try:
            result = call()
        except (ConnectionError, ValueError) as exc:
            result = "%s: %s" % (failed, exc)
        except Exception as exc:  # the panel must always give an answer
            result = "%s: %r" % (failed, exc)
        events.put((kind, result))

    threading.Thread(target=work, name=name, daemon=True).start()

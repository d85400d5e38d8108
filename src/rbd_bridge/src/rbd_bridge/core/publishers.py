"""Which ROS publishers the bridge holds for its clients, and when one nobody uses goes (ROS-free).

One publisher per topic is shared by every client that advertised it. When the last one
leaves, the publisher lingers (``linger`` seconds, 0 = goes at once) before the ROS edge
unregisters it: a ROS subscriber whose connection meets an unregister is refused, and rospy
then never connects it to the next advertise of the topic (a laptop that reconnects). A
client advertising a lingering topic with its type and latching gets the same publisher back
(:meth:`Publication.revive`); another type or latching replaces it.
"""

import time
from typing import Any, Callable, List, Optional, Tuple

from rbd_bridge.core.types import BridgeError

__all__ = ["Publication", "Publications"]


class Publication:
    """One topic's publisher: its type, latching, the clients using it, its expiry when idle."""

    def __init__(self, type_name: str, latch: bool) -> None:
        """Nobody uses it yet."""
        self.type = type_name
        self.latch = latch
        self.clients = set()
        self.deadline = None  # monotonic time it goes when nobody uses it

    def revive(self) -> None:
        """Hook: a client took the lingering publication up again (the ROS edge reopens its window)."""


class Publications:
    """The publications by topic, with the linger rule.

    Args:
        linger: Seconds an unused publication is kept (0 = released at once).
        clock: Monotonic time source [s].
    """

    def __init__(self, linger: float, clock: Callable[[], float] = time.monotonic) -> None:
        """No publication yet."""
        self.linger = linger
        self.clock = clock
        self.held = {}

    def get(self, topic: str) -> Optional[Publication]:
        """The publication of topic, also a lingering one (None if none)."""
        return self.held.get(topic)

    def join(self, topic: str, type_name: str, latch: bool, client: Any) -> Tuple[Any, Any]:
        """Let client use topic's publication if there is a fitting one.

        Returns:
            (the publication client now uses, or None: make one and :meth:`add` it;
            a lingering publication of another type or latching to unregister first, or None).

        Raises:
            BridgeError: Other clients use topic with another type.
        """
        held = self.held.get(topic)
        if held is None:
            return None, None
        if held.type == type_name and (held.clients or held.latch == latch):
            if not held.clients:
                held.deadline = None
                held.revive()
            held.clients.add(client)
            return held, None
        if held.clients:
            raise BridgeError("advertise: %s is already advertised with type %s" % (topic, held.type))
        return None, self.held.pop(topic)

    def add(self, topic: str, publication: Publication, client: Any) -> None:
        """Hold a new publication of topic, used by client."""
        publication.clients.add(client)
        self.held[topic] = publication

    def leave(self, topic: str, client: Any) -> Tuple[Optional[Publication], float]:
        """Client no longer uses topic.

        Returns:
            (the publication to unregister now, or None; seconds until :meth:`sweep` is due, 0 = none).
        """
        held = self.held.get(topic)
        if held is None or client not in held.clients:
            return None, 0.0
        held.clients.discard(client)
        if held.clients:
            return None, 0.0
        if self.linger <= 0:
            return self.held.pop(topic), 0.0
        held.deadline = self.clock() + self.linger
        return None, self.linger

    def sweep(self) -> Tuple[List[Publication], float]:
        """Remove the publications that lingered long enough.

        Returns:
            (those to unregister now; seconds until the next one is due, 0 = none lingers).
        """
        now, gone, due = self.clock(), [], []
        for topic, held in list(self.held.items()):
            if held.deadline is not None and not held.clients:
                if held.deadline <= now:
                    gone.append(self.held.pop(topic))
                else:
                    due.append(held.deadline - now)
        return gone, min(due) if due else 0.0

"""The bridge's ROS publishers by topic, and the linger of one nobody uses any more (ROS-free; README)."""

import time
from typing import Any, Callable, List, Tuple

from rbd_bridge.core.types import BridgeError

__all__ = ["Publication", "Publications"]


class Publication:
    """One topic's publisher: type, latching, the clients using it, its deadline while unused."""

    def __init__(self, type_name: str, latch: bool) -> None:
        self.type = type_name
        self.latch = latch
        self.clients = set()
        self.deadline = None

    def revive(self) -> None:
        """Hook: a client took it up again while it lingered."""


class Publications:
    """The publications by topic (``held``), lingering ``linger`` seconds when unused."""

    def __init__(self, linger: float, clock: Callable[[], float] = time.monotonic) -> None:
        self.linger = linger
        self.clock = clock
        self.held = {}

    def join(self, topic: str, type_name: str, latch: bool, client: Any) -> Tuple[Any, Any]:
        """Let client use topic's publication if one fits.

        Returns:
            (the publication client now uses, or None: make one and :meth:`add` it;
            a lingering publication to unregister first, or None).

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

    def leave(self, topic: str, client: Any) -> Tuple[List[Publication], float]:
        """Client no longer uses topic: (publications to unregister now, seconds until :meth:`sweep` is due or 0)."""
        held = self.held.get(topic)
        if held is None or client not in held.clients:
            return [], 0.0
        held.clients.discard(client)
        if held.clients:
            return [], 0.0
        if self.linger <= 0:
            return [self.held.pop(topic)], 0.0
        held.deadline = self.clock() + self.linger
        return [], self.linger

    def sweep(self) -> Tuple[List[Publication], float]:
        """Remove what lingered long enough: (those to unregister now, seconds until the next is due or 0)."""
        now, gone, due = self.clock(), [], []
        for topic, held in list(self.held.items()):
            if held.deadline is not None and not held.clients:
                if held.deadline <= now:
                    gone.append(self.held.pop(topic))
                else:
                    due.append(held.deadline - now)
        return gone, min(due) if due else 0.0

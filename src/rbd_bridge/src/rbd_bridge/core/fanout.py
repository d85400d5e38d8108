"""One topic message on its way to many clients: encode once, send directly or queue; replay window. ROS-free."""

import collections
import json
import logging
import threading
import time
from typing import Any, Callable, Iterable, List

from rbd_bridge.core import encoding

__all__ = ["TopicMessage", "ReplayWindow", "prepare", "send_direct", "deliver"]

_log = logging.getLogger("rbd_bridge")


class TopicMessage:
    """One ROS message on its way to clients, encoded at most once per compression.

    ``to_dict(binary)`` gives the message as a JSON-ready dict (binary=True: for CBOR);
    ``raw()`` gives (serialized bytes, secs, nsecs) for ``cbor-raw``.
    """

    __slots__ = ("topic", "_to_dict", "_raw", "_frames", "latched", "wired")

    def __init__(
        self, topic: str, to_dict: Callable[..., Any], raw: Callable[..., Any] = None, latched: Any = False
    ) -> None:
        self.topic = topic
        self._to_dict = to_dict
        self._raw = raw
        self._frames = {}
        self.latched = latched
        self.wired = {}  # the transport's frames by compression (see wire)

    def frame(self, compression: str) -> Any:
        """Return the whole ``publish`` frame (str for none/png, bytes for cbor*)."""
        frame = self._frames.get(compression)
        if frame is not None:
            return frame
        if compression == "none":
            msg = encoding.json_dumps(self._to_dict(False))
            frame = '{"op":"publish","topic":%s,"msg":%s}' % (json.dumps(self.topic), msg)
        elif compression == "cbor":
            frame = encoding.cbor_dumps({"op": "publish", "topic": self.topic, "msg": self._to_dict(True)})
        elif compression == "cbor-raw":
            data, secs, nsecs = self._raw()
            msg = {"secs": secs, "nsecs": nsecs, "bytes": data}
            frame = encoding.cbor_dumps({"op": "publish", "topic": self.topic, "msg": msg})
        else:
            raise ValueError(compression)
        self._frames[compression] = frame
        return frame

    def wire(self, compression: str, make: Callable[[Any], bytes]) -> bytes:
        """The frame as the transport sends it (``make(frame)``, cached: one transport per process)."""
        wire = self.wired.get(compression)
        if wire is None:
            wire = self.wired[compression] = make(self.frame(compression))
        return wire


def prepare(message: TopicMessage, sessions: Iterable[Any]) -> bool:
    """Encode message once per compression the sessions want (png is made from none); False (logged) if it cannot."""
    wanted = set()
    for session in sessions:
        sub = session.subs.get(message.topic)
        if sub is not None:
            wanted.add("none" if sub.compression == "png" else sub.compression)
    try:
        for compression in wanted:
            message.frame(compression)
    except Exception as exc:
        _log.error("topic %s: cannot decode or encode a message: %s", message.topic, exc)
        return False
    return True


def send_direct(message: TopicMessage, sessions: Iterable[Any]) -> List[Any]:
    """Send message at once to every session that can take it directly; return the others.

    A session can when its subscription has no throttle, fragmentation or PNG and its
    transport has nothing queued (``Session.direct_compression`` / ``Session.direct``):
    then the frame is exactly what :meth:`Session.deliver` would queue, and order holds.
    """
    rest = []
    for session in sessions:
        compression = session.direct_compression(message.topic)
        try:
            sent = compression is not None and session.direct(message, compression)
        except Exception:
            _log.exception("direct send to client %s failed", session.client_id)
            sent = False
        if not sent:
            rest.append(session)
    return rest


def deliver(message: TopicMessage, sessions: Iterable[Any], subscribed: Any) -> None:
    """Hand message to each of sessions still in subscribed (its throttle and queue decide); errors are logged."""
    for session in sessions:
        if session in subscribed:
            try:
                session.deliver(message.topic, message)
            except Exception:
                _log.exception("delivery to client %s failed", session.client_id)


class ReplayWindow:
    """What was published in the first seconds after advertise, for subscribers still connecting.

    A ROS subscriber connects only after the master told it about a new publisher, so a
    client that advertises and publishes at once would lose those messages (rosbridge keeps
    them for 1 s). Messages published while the window (``seconds``, 0 = off) is open, at
    most ``limit`` (the newest), are replayed to each subscriber connection made in it,
    before anything newer (for a latched publisher without the last: the latch resends it).
    The publishing thread holds ``lock`` around :meth:`record` and the publish; the thread
    adding a connection holds it around adding and :meth:`replay`.
    """

    def __init__(self, seconds: float, limit: int, latch: bool, clock: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self.seconds = seconds
        self.messages = collections.deque(maxlen=max(1, limit))
        self.latch = latch
        self.lock = threading.RLock()
        self.reopen()

    def reopen(self) -> None:
        """Open the window now, empty (also for a lingering publisher advertised again)."""
        self.deadline = self.clock() + self.seconds if self.seconds > 0 else 0.0
        self.messages.clear()

    def is_open(self) -> bool:
        """True while messages are kept."""
        return bool(self.deadline) and self.clock() < self.deadline

    def record(self, message: Any) -> None:
        """Keep message while the window is open (caller holds :attr:`lock`)."""
        if self.is_open():
            self.messages.append(message)
        elif self.deadline:
            self.deadline = 0.0
            self.messages.clear()

    def replay(self) -> List[Any]:
        """Messages for a subscriber connecting now (caller holds :attr:`lock`); empty once closed."""
        if not self.is_open():
            return []
        kept = list(self.messages)
        return kept[:-1] if self.latch else kept

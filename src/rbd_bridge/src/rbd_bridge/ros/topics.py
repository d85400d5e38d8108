"""Topics: one rospy.Publisher and one rospy.Subscriber per topic, shared by all clients.

Publishes right after an advertise are replayed to subscribers still connecting
(:class:`rbd_bridge.core.fanout.ReplayWindow`); an unused publisher lingers
(:mod:`rbd_bridge.core.publishers`). Without the fast path, messages from ROS arrive in
rospy's threads: isolated ones go straight to idle clients, bursts through the event loop.
"""

import collections
import contextlib
import io
import logging
import threading
import time
from typing import Any, Optional

import rospy

from rbd_bridge.core.fanout import ReplayWindow, TopicMessage, deliver, prepare, send_direct
from rbd_bridge.core.publishers import Publication, Publications
from rbd_bridge.core.types import BridgeError, ConversionError, normalize_type
from rbd_bridge.ros.msgconv import dict_to_msg, get_message_class, msg_to_dict

__all__ = ["Topics"]

_log = logging.getLogger("rbd_bridge")
_BURST_GAP = 0.0002  # messages of a topic closer than this [s] are a burst: sent via the loop, not directly
_RECV_SIZE = 65536  # rospy's recv() size per read of a subscribed topic [bytes]


class _Pub(Publication, rospy.SubscribeListener):
    """A topic's publisher; as rospy's hook for a new subscriber connection it replays the advertise window."""

    def __init__(self, type_name: str, latch: bool, cls: Any, window: ReplayWindow) -> None:
        super().__init__(type_name, latch)
        self.cls = cls
        self.window = window
        self.publisher = None

    def revive(self) -> None:
        with self.window.lock:
            self.window.reopen()

    def peer_subscribe(self, topic_name: str, topic_publish: Any, peer_publish: Any) -> None:
        with self.window.lock:
            for message in self.window.replay():
                peer_publish(message)


class _Sub:
    def __init__(self, topic: str, type_name: str, cls: Any) -> None:
        self.topic = topic
        self.type = type_name
        self.cls = cls
        self.subscriber = None
        self.sessions = set()
        self.latched = {}  # latched messages by publisher (callerid)
        self.last_rx = -1.0


class Topics:
    """The topic half of the backend.

    Args:
        loop: The event loop the sessions live on.
        master: rosgraph.Master-like (topic types).
        window: Seconds after advertise whose publishes new subscribers still get (0 = off).
        fast: :class:`rbd_bridge.ros.fastpath.FastPath`, or None for plain rospy.
        linger: Seconds a publisher nobody uses stays registered (0 = unregistered at once).
    """

    def __init__(self, loop: Any, master: Any, window: float = 1.0, fast: Any = None, linger: float = 5.0) -> None:
        self.loop = loop
        self.master = master
        self.window = window
        self.fast = fast
        self.pubs = Publications(linger)
        self._sweeping = None
        self.subs = {}
        self.rospy_read_messages = 0  # not locked: approximate under concurrent publishers
        self._inbox = collections.deque()
        self._inbox_lock = threading.Lock()
        self._draining = False

    def master_type(self, topic: str) -> Optional[str]:
        """The type the master knows for topic (None if none, or only ``*``)."""
        try:
            type_name = dict(self.master.getTopicTypes()).get(topic)
        except Exception as exc:
            raise BridgeError("cannot reach the ROS master: %s" % exc) from None
        return None if type_name == "*" else type_name

    def advertise(self, session: Any, topic: str, type_name: str, latch: bool, queue_size: int) -> None:
        """Register session as publisher of topic (one rospy.Publisher per topic)."""
        type_name, cls = normalize_type(type_name), get_message_class(type_name)
        pub, stale = self.pubs.join(topic, type_name, latch, session.client_id)
        if stale is not None:
            stale.publisher.unregister()
        if pub is None:
            existing = self.master_type(topic)
            if existing and existing != type_name:
                raise BridgeError("advertise: %s already exists with type %s" % (topic, existing))
            pub = _Pub(type_name, latch, cls, ReplayWindow(self.window, queue_size, latch))
            if self.fast is not None:
                pub.publisher = self.fast.publisher(topic, cls, queue_size, latch, pub, pub.window)
            else:
                pub.publisher = rospy.Publisher(topic, cls, queue_size=queue_size, latch=latch, subscriber_listener=pub)
            self.pubs.add(topic, pub, session.client_id)

    def unadvertise(self, session: Any, topic: str) -> None:
        """Drop session from topic's publishers; unregister after the linger when nobody is left."""
        self._unregister(*self.pubs.leave(topic, session.client_id))

    def _unregister(self, gone: Any, due: float) -> None:
        """Unregister gone's publishers; sweep the lingering ones in due seconds (0 = none left)."""
        for pub in gone:
            pub.publisher.unregister()
        if due and self._sweeping is None:
            self._sweeping = self.loop.call_later(due, self._sweep)

    def _sweep(self) -> None:
        self._sweeping = None
        self._unregister(*self.pubs.sweep())

    def publish(self, session: Any, topic: str, msg: Any) -> Any:
        """Publish msg (advertising implicitly with the type the master knows); return defaulted fields."""
        pub = self.pubs.held.get(topic)
        if pub is None or session.client_id not in pub.clients:
            type_name = pub.type if pub is not None else self.master_type(topic)
            if not type_name:
                raise BridgeError("publish: cannot infer the type of %s (advertise it first)" % topic)
            self.advertise(session, topic, type_name, pub is not None and pub.latch, 100)
            pub = self.pubs.held[topic]
        try:
            message, missing = dict_to_msg(pub.cls, msg, rospy.Time.now)
            with pub.window.lock:
                pub.window.record(message)
                pub.publisher.publish(message)
        except (ConversionError, rospy.ROSSerializationException) as exc:
            raise BridgeError("publish %s: %s" % (topic, exc)) from None
        return missing

    def subscribe(self, session: Any, topic: str, type_name: Optional[str]) -> str:
        """Share one rospy.Subscriber per topic among all sessions; return the type."""
        sub = self.subs.get(topic)
        existing = sub.type if sub is not None else self.master_type(topic)
        if not type_name and not existing:
            raise BridgeError("subscribe: cannot infer the type of %s (it does not exist yet; give 'type')" % topic)
        type_name = normalize_type(type_name or existing)
        if existing and existing != type_name:
            raise BridgeError("subscribe: %s has type %s, not %s" % (topic, existing, type_name))
        if sub is not None:
            sub.sessions.add(session)
            for message in list(sub.latched.values()):
                self.loop.call_soon(session.deliver, topic, message)
            return sub.type
        cls = get_message_class(type_name)
        sub = self.subs[topic] = _Sub(topic, type_name, cls)
        sub.sessions.add(session)
        # queue_size=None: all of a read is handed over (OutQueue bounds a slow client); each
        # recv allocates buff_size (1 MiB cost ~0.1 ms per message), big messages take several
        sub.subscriber = rospy.Subscriber(
            topic, cls, self._on_message, callback_args=sub, queue_size=None, buff_size=_RECV_SIZE, tcp_nodelay=True
        )
        if self.fast is not None:
            self.fast.read_directly(sub)
        return type_name

    def unsubscribe(self, session: Any, topic: str) -> None:
        """Remove session; unregister the rospy.Subscriber when nobody is left."""
        sub = self.subs.get(topic)
        if sub is not None:
            sub.sessions.discard(session)
            if not sub.sessions:
                del self.subs[topic]
                sub.subscriber.unregister()

    def release(self, session: Any) -> None:
        """Drop every publisher and subscription of a gone client."""
        for topic in list(session.advertised):
            self.unadvertise(session, topic)
        for topic, sub in list(self.subs.items()):
            if session in sub.sessions:
                self.unsubscribe(session, topic)

    def _on_message(self, msg: Any, sub: Any) -> None:
        """Rospy thread: wrap the message, encode what subscribers want, send or hop to the loop."""
        self.rospy_read_messages += 1
        header = getattr(msg, "_connection_header", None) or {}
        latched = header.get("latching") == "1"
        stamp = rospy.get_rostime()

        def raw() -> Any:
            buff = io.BytesIO()
            msg.serialize(buff)
            return buff.getvalue(), stamp.secs, stamp.nsecs

        message = TopicMessage(sub.topic, lambda binary: msg_to_dict(msg, binary), raw, latched)
        sessions = list(sub.sessions)
        if not prepare(message, sessions):
            return
        if latched:
            sub.latched[header.get("callerid", "")] = message
        now = time.monotonic()
        burst = now - sub.last_rx < _BURST_GAP
        sub.last_rx = now
        rest = None
        with self._inbox_lock:
            if not burst and not self._inbox and not self._draining and not latched:
                # nothing older is on its way: idle clients get it from this thread
                rest = send_direct(message, sessions)
                if not rest:
                    return
            wake = not self._inbox
            self._inbox.append((sub, message, rest))
        if wake:  # one loop wake-up per burst, not per message
            with contextlib.suppress(RuntimeError):  # loop closed: shutting down
                self.loop.call_soon_threadsafe(self._drain_inbox)

    def _drain_inbox(self) -> None:
        while True:
            with self._inbox_lock:
                if not self._inbox:
                    self._draining = False
                    return
                items, self._inbox = self._inbox, collections.deque()
                self._draining = True  # no direct send may overtake these
            for sub, message, only in items:
                deliver(message, list(sub.sessions) if only is None else only, sub.sessions)

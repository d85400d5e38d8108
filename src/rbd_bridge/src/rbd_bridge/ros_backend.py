"""The ROS side of the bridge (rospy): publishers, shared subscribers, service calls/hosting.

All :class:`rbd_bridge.protocol.Backend` methods run on the server's asyncio loop thread;
rospy callbacks run on rospy's threads and hop to the loop with ``call_soon_threadsafe``.
With ``direct_reads`` (the default) rospy still registers subscriptions and makes each
TCPROS connection (handshake included), but then the connection's socket is read by the
event loop itself (:class:`rbd_bridge.tcpros.LoopReader`): no receive thread, no hop, and
a message is deserialized only when a client needs it as JSON or CBOR. If taking over a
connection fails, rospy's own receive loop serves it as before.
Blocking ROS calls (services, master look-ups for rosapi, parameters) run in a thread pool.
"""

import collections
import concurrent.futures
import functools
import io
import itertools
import logging
import socket
import threading
import time
import warnings
from typing import Any, Callable, Optional

import rosgraph
import rospy
import rosservice
from rospy.exceptions import TransportTerminated
from rospy.impl.tcpros_base import TCPROSTransport
from rospy.topics import _PublisherImpl

from rbd_bridge.msgconv import (
    ConversionError,
    dict_to_msg,
    get_message_class,
    get_service_class,
    msg_to_dict,
    normalize_type,
)
from rbd_bridge.protocol import Backend, BridgeError, TopicMessage
from rbd_bridge.rosapi import RosApi, RosApiError
from rbd_bridge.tcpros import LoopReader

__all__ = ["RosBackend"]

_log = logging.getLogger("rbd_bridge")

# Messages of one topic closer together than this [s] are a burst: they go through the
# event loop, which writes a whole burst per wake-up; isolated ones are sent directly.
_BURST_GAP = 0.0002
_RECV_SIZE = 65536  # rospy recv() size per read of a subscribed topic [bytes]
_ADOPT_TIMEOUT = 5.0  # a ROS thread waits this long for the loop to take a connection [s]
# At most this many publishes leave in one write to a ROS subscriber: rospy keeps only the
# newest queue_size messages of each read, so one big write of a client's burst made a
# queue-1000 subscriber drop what arrived beyond 1000 (measured: 95-97 % of 5000 delivered).
_CORK_MESSAGES = 32


class _Pub:
    __slots__ = ("topic", "type", "cls", "publisher", "clients", "window")

    def __init__(self, topic: str, type_name: str, cls: Any, publisher: Any, window: Any) -> None:
        self.topic = topic
        self.type = type_name
        self.cls = cls
        self.publisher = publisher
        self.clients = set()
        self.window = window


class _AdvertiseWindow(rospy.SubscribeListener):
    """Keeps what is published in the first seconds after advertise for subscribers still connecting.

    A ROS subscriber connects only after the master told it about the new publisher, so a
    client that advertises and publishes at once would otherwise lose those messages
    (rosbridge keeps them for 1 s). Messages published while the window is open (at most
    ``limit``, the newest kept) are sent to every subscriber connection made in the window,
    before anything newer. ``lock`` orders publishes and replays (taken by the publishing
    thread around ``publish`` and by rospy's thread around the connection being added).
    """

    def __init__(self, seconds: float, limit: int, latch: bool) -> None:
        super().__init__()
        self.deadline = time.monotonic() + seconds
        self.messages = collections.deque(maxlen=max(1, limit))
        self.latch = latch
        self.lock = threading.RLock()

    def is_open(self) -> bool:
        return self.deadline > 0 and time.monotonic() < self.deadline

    def record(self, message: Any) -> None:
        """Publishing thread, with ``lock`` held: keep message while the window is open."""
        if self.is_open():
            self.messages.append(message)
        elif self.messages:
            self.messages.clear()
            self.deadline = 0.0

    def peer_subscribe(self, topic_name: str, topic_publish: Any, peer_publish: Callable[..., Any]) -> None:
        """Rospy thread: a subscriber connected; replay the window to it (the latch sends the last)."""
        with self.lock:
            if not self.is_open():
                return
            kept = list(self.messages)
            for message in kept[:-1] if self.latch else kept:
                peer_publish(message)


class _Cork:
    """Holds the event loop's publishes while one client read is handled (one send per peer).

    Set by :meth:`RosBackend.begin_batch` / :meth:`RosBackend.end_batch`; only writes from
    the thread that set it are held.
    """

    __slots__ = ("thread", "pending")

    def __init__(self) -> None:
        self.thread = None
        self.pending = []


class _DirectConnection:
    """A rospy publisher connection that writes at once when it can, never blocking the caller.

    rospy's own queued connection hands every message to a writer thread and yields the GIL
    (``time.sleep(0)``) on each publish; that thread hop dominated the bridge's publish path.
    Here the publishing thread (the event loop) tries a non-blocking ``send`` first; only
    what the kernel does not take at once (a slow or stuck ROS subscriber) goes to a bounded
    backlog that this connection's writer thread sends with blocking writes, in order. So a
    stuck subscriber never blocks the event loop, costs at most ``queue_size`` messages, and
    never delays other subscribers (each connection has its own backlog and thread).
    """

    def __init__(self, connection: Any, queue_size: int, cork: Any = None) -> None:
        self._connection = connection
        self._cork = cork
        self._parts = None  # writes held by the cork
        self._queue_size = max(1, queue_size)
        self._lock = threading.RLock()  # conn.close() calls _closed with it held
        self._wake = threading.Condition(self._lock)
        self._backlog = collections.deque()
        self._busy = False
        self._error = None
        self._thread = None
        self.dropped = 0
        connection.set_cleanup_callback(self._closed)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self._connection, name)

    def _closed(self, _connection: Any) -> None:
        with self._lock:
            self._wake.notify()

    def write_data(self, data: bytes) -> bool:
        """Send data now if the socket takes it; else queue it for the writer thread.

        While the cork is set by the calling thread, data is held until :meth:`uncork`, or
        until ``_CORK_MESSAGES`` messages are held (then they leave together).
        """
        cork = self._cork
        if cork is not None and cork.thread == threading.get_ident():
            with self._lock:
                if self._error is not None:
                    error, self._error = self._error, None
                    raise error
                if self._connection.done:
                    raise TransportTerminated("connection closed")
                if self._parts is None:
                    self._parts = [data]
                    cork.pending.append(self)
                    return True
                self._parts.append(data)
                if len(self._parts) < _CORK_MESSAGES:
                    return True
                parts, self._parts = self._parts, []
            return self._write(b"".join(parts))
        return self._write(data)

    def uncork(self) -> None:
        """Send the held writes as one (errors close the connection; rospy sees it next time)."""
        with self._lock:
            parts, self._parts = self._parts, None
        if not parts:
            return
        try:
            self._write(parts[0] if len(parts) == 1 else b"".join(parts))
        except TransportTerminated:
            pass
        except Exception:
            _log.exception("publisher connection to %s failed", self._connection.endpoint_id)

    def _write(self, data: bytes) -> bool:
        conn = self._connection
        with self._lock:
            if self._error is not None:
                error, self._error = self._error, None
                raise error
            if conn.done:
                raise TransportTerminated("connection closed")
            if not self._busy:
                sock = conn.socket
                if sock is None:
                    raise TransportTerminated("connection not initialised")
                try:
                    sent = sock.send(data, socket.MSG_DONTWAIT)
                except (BlockingIOError, InterruptedError):
                    sent = 0
                except OSError as exc:
                    conn.close()
                    raise TransportTerminated(str(exc)) from None
                if sent == len(data):
                    conn.stat_bytes += sent
                    conn.stat_num_msg += 1
                    return True
                # the head of the backlog is the unsent rest of a message: never dropped
                self._backlog.append(memoryview(data)[sent:])
                self._busy = True
                if self._thread is None:
                    self._thread = threading.Thread(target=self._run, name="rbd_bridge_pub", daemon=True)
                    self._thread.start()
                else:
                    self._wake.notify()
                return True
            if len(self._backlog) > self._queue_size:
                # drop the oldest whole message (never the partly sent head)
                head = self._backlog.popleft()
                self._backlog.popleft()
                self._backlog.appendleft(head)
                self.dropped += 1
            self._backlog.append(data)
            self._wake.notify()
        return True

    def _run(self) -> None:
        conn = self._connection
        while True:
            with self._lock:
                while not self._backlog and not conn.done:
                    self._busy = False
                    self._wake.wait()
                if conn.done:
                    self._backlog.clear()
                    return
                self._busy = True
                data = self._backlog.popleft()
            try:
                conn.socket.sendall(data)
                conn.stat_bytes += len(data)
                conn.stat_num_msg += 1
            except Exception as exc:
                with self._lock:
                    self._error = TransportTerminated(str(exc))
                    self._backlog.clear()
                try:
                    conn.close()
                except Exception:
                    pass
                return


def _direct_publisher(topic: str, cls: Any, queue_size: int, latch: bool, window: Any, cork: Any = None) -> Any:
    """A rospy.Publisher whose connections are :class:`_DirectConnection` s."""
    with warnings.catch_warnings():  # queue_size=None is deliberate: the queue is ours
        warnings.simplefilter("ignore")
        publisher = rospy.Publisher(topic, cls, queue_size=None, latch=latch, subscriber_listener=window)
    impl = publisher.impl
    if not getattr(impl, "_rbd_direct", False):
        # one impl per topic in this process; wrap each connection rospy hands to it
        def add_connection(connection: Any) -> Any:
            with window.lock:  # no publish between adding the connection and replaying the window
                return _PublisherImpl.add_connection(impl, _DirectConnection(connection, queue_size, cork))

        impl.add_connection = add_connection
        impl._rbd_direct = True
    return publisher


class _LazyMessage:
    """A received message kept serialized until a client needs it as a dict."""

    __slots__ = ("cls", "payload", "msg")

    def __init__(self, cls: Any, payload: bytes) -> None:
        self.cls = cls
        self.payload = payload
        self.msg = None

    def to_dict(self, binary: bool) -> Any:
        msg = self.msg
        if msg is None:
            msg = self.cls()
            msg.deserialize(self.payload)
            self.msg = msg
        return msg_to_dict(msg, binary)


class _Sub:
    __slots__ = ("topic", "type", "cls", "subscriber", "sessions", "latched", "last_rx")

    def __init__(self, topic: str, type_name: str, cls: Any) -> None:
        self.topic = topic
        self.type = type_name
        self.cls = cls
        self.subscriber = None
        self.sessions = set()
        self.latched = {}
        self.last_rx = -1.0


class _Hosted:
    """A service that a WebSocket client provides to ROS."""

    def __init__(self, backend: Any, name: str, type_name: str, cls: Any, session: Any) -> None:
        self.backend = backend
        self.name = name
        self.type = type_name
        self.cls = cls
        self.session = session
        self.pending = {}
        self.lock = threading.Lock()
        self.closed = False
        self.server = None
        self.false_results = 0

    def handle(self, request: Any) -> Any:
        """Rospy thread: forward the request to the client and wait for its answer."""
        call_id = "service_request:%s:%d" % (self.name, next(self.backend.ids))
        waiter = [threading.Event(), None, None]
        with self.lock:
            if self.closed:
                raise rospy.ServiceException("service %s: its WebSocket provider is gone" % self.name)
            self.pending[call_id] = waiter
        args = msg_to_dict(request)
        loop = self.backend.loop
        loop.call_soon_threadsafe(self.session.send_service_request, self.name, call_id, args)
        if not waiter[0].wait(self.backend.service_timeout):
            with self.lock:
                self.pending.pop(call_id, None)
            raise rospy.ServiceException(
                "service %s: WebSocket provider did not answer in %.1f s" % (self.name, self.backend.service_timeout)
            )
        ok, values = waiter[1], waiter[2]
        if not ok and not isinstance(values, dict):
            raise rospy.ServiceException("service %s failed: %s" % (self.name, values))
        if not ok:
            # rosbridge ignores the flag and returns the values (roslibpy handlers that
            # return False rely on it); say so once per service
            self.false_results += 1
            if self.false_results == 1:
                _log.warning(
                    "service %s: its WebSocket provider answered result=false; the values are returned"
                    " to the caller as rosbridge does (logged once)",
                    self.name,
                )
        try:
            response, _ = dict_to_msg(self.cls._response_class, values if isinstance(values, dict) else {})
        except ConversionError as exc:
            raise rospy.ServiceException(
                "service %s: bad response from WebSocket provider: %s" % (self.name, exc)
            ) from None
        return response

    def answer(self, call_id: Any, ok: bool, values: Any) -> bool:
        with self.lock:
            waiter = self.pending.pop(call_id, None)
        if waiter is None:
            return False
        waiter[1], waiter[2] = ok, values
        waiter[0].set()
        return True

    def close(self, reason: str) -> None:
        with self.lock:
            self.closed = True
            pending, self.pending = self.pending, {}
        for waiter in pending.values():
            waiter[1], waiter[2] = False, reason
            waiter[0].set()
        if self.server is not None:
            self.server.shutdown(reason)


class _ThreadLocalMaster:
    """rosgraph.Master per thread (an XML-RPC ServerProxy must not be shared by threads)."""

    def __init__(self, caller_id: str) -> None:
        self._caller_id = caller_id
        self._local = threading.local()

    def __getattr__(self, name: str) -> Any:
        master = getattr(self._local, "master", None)
        if master is None:
            master = self._local.master = rosgraph.Master(self._caller_id)
        return getattr(master, name)


class _RosParams:
    """Parameter adapter for rosapi on the real parameter server."""

    def get(self, name: str) -> Any:
        return rospy.get_param(name)

    def set(self, name: str, value: Any) -> None:
        rospy.set_param(name, value)

    def has(self, name: str) -> Any:
        return rospy.has_param(name)

    def delete(self, name: str) -> None:
        rospy.delete_param(name)

    def search(self, name: str) -> Any:
        return rospy.search_param(name)

    def names(self) -> Any:
        return rospy.get_param_names()


def _is_transport_error(exc: Any) -> Any:
    if isinstance(exc, (rospy.exceptions.TransportException, socket.error, EOFError)):
        return True
    text = str(exc).lower()
    return "transport error" in text or "unable to connect" in text or "connection" in text


class RosBackend(Backend):
    """rospy implementation of the protocol backend.

    Args:
        loop: The asyncio loop the sessions live on.
        policy: The bridge :class:`rbd_bridge.security.Policy` (for rosapi filtering).
        service_timeout: Seconds a ROS caller waits for a client-hosted service.
        call_timeout: Default seconds for ``call_service`` without ``timeout`` (0 = none).
        workers: Threads for blocking calls.
        direct_reads: Read subscribed TCPROS connections in the event loop (module doc).
        fail_direct_reads: Test hook: every take-over fails, so rospy's receive threads
            serve all connections (the fallback path).
        advertise_window: Seconds after advertise during which published messages are kept
            for subscribers still connecting (:class:`_AdvertiseWindow`; 0 = off).
    """

    def __init__(
        self,
        loop: Any,
        policy: Any,
        service_timeout: float = 10.0,
        call_timeout: float = 30.0,
        workers: int = 8,
        direct_reads: bool = True,
        fail_direct_reads: bool = False,
        advertise_window: float = 1.0,
    ) -> None:
        """Create the backend (rospy.init_node must have been called)."""
        self.loop = loop
        self.advertise_window = advertise_window
        self.direct_reads = direct_reads
        self.fail_direct_reads = fail_direct_reads
        self._readers = {}  # rospy connection -> LoopReader (loop thread only)
        self._cork = _Cork()
        self._cork_depth = 0
        # counters for the ~stats service; rospy-thread ones are approximate under races
        self.counters = {
            "direct_read_connections": 0,
            "direct_read_messages": 0,
            "direct_read_fallbacks": 0,
            "rospy_read_messages": 0,
        }
        self.policy = policy
        self.service_timeout = service_timeout
        self.call_timeout = call_timeout
        self.pubs = {}
        self.subs = {}
        self.hosted = {}
        self.ids = itertools.count(1)
        self.pool = concurrent.futures.ThreadPoolExecutor(max_workers=workers, thread_name_prefix="rbd_bridge_call")
        self.master = _ThreadLocalMaster(rospy.get_name())
        self._proxies = {}
        self._proxy_lock = threading.Lock()
        self._srv_types = {}
        self._inbox = collections.deque()
        self._inbox_lock = threading.Lock()
        self._draining = False
        self.rosapi = RosApi(policy, self.master, _RosParams(), self._now, self._lookup_service_type)

    # ------------------------------------------------------------ helpers

    @staticmethod
    def _now() -> Any:
        t = rospy.get_rostime()
        return t.secs, t.nsecs

    def _master_type(self, topic: str) -> Any:
        try:
            for name, type_name in self.master.getTopicTypes():
                if name == topic:
                    return type_name
        except Exception as exc:
            raise BridgeError("cannot reach the ROS master: %s" % exc) from None
        return None

    @staticmethod
    def _message_class(type_name: str) -> Any:
        try:
            return normalize_type(type_name), get_message_class(type_name)
        except ConversionError as exc:
            raise BridgeError(str(exc)) from None

    # ------------------------------------------------------------ topics out to ROS

    def advertise(self, session: Any, topic: str, type_name: str, latch: bool, queue_size: int) -> None:
        """Register session as publisher of topic (one rospy.Publisher per topic)."""
        type_name, cls = self._message_class(type_name)
        pub = self.pubs.get(topic)
        if pub is not None:
            if pub.type != type_name:
                raise BridgeError("advertise: %s is already advertised with type %s" % (topic, pub.type))
            pub.clients.add(session.client_id)
            return
        existing = self._master_type(topic)
        if existing and existing != type_name and existing != "*":
            raise BridgeError("advertise: %s already exists with type %s" % (topic, existing))
        window = _AdvertiseWindow(self.advertise_window, queue_size, latch)
        publisher = _direct_publisher(topic, cls, queue_size, latch, window, self._cork)
        pub = _Pub(topic, type_name, cls, publisher, window)
        pub.clients.add(session.client_id)
        self.pubs[topic] = pub

    def unadvertise(self, session: Any, topic: str) -> None:
        """Drop session from topic's publishers; unregister when nobody is left."""
        pub = self.pubs.get(topic)
        if pub is None:
            return
        pub.clients.discard(session.client_id)
        if not pub.clients:
            del self.pubs[topic]
            pub.publisher.unregister()

    def publish(self, session: Any, topic: str, msg: Any) -> Any:
        """Publish msg; advertise implicitly with the type known to the master."""
        pub = self.pubs.get(topic)
        if pub is None or session.client_id not in pub.clients:
            if pub is None:
                type_name = self._master_type(topic)
                if not type_name or type_name == "*":
                    raise BridgeError("publish: cannot infer the type of %s (advertise it first)" % topic)
            else:
                type_name = pub.type
            self.advertise(session, topic, type_name, False, 100)
            pub = self.pubs[topic]
        try:
            message, missing = dict_to_msg(pub.cls, msg, rospy.Time.now)
        except ConversionError as exc:
            raise BridgeError("publish %s: %s" % (topic, exc)) from None
        try:
            with pub.window.lock:
                pub.window.record(message)
                pub.publisher.publish(message)
        except rospy.ROSSerializationException as exc:
            raise BridgeError("publish %s: %s" % (topic, exc)) from None
        return missing

    # ------------------------------------------------------------ topics in from ROS

    def subscribe(self, session: Any, topic: str, type_name: str) -> Any:
        """Share one rospy.Subscriber per topic among all sessions."""
        sub = self.subs.get(topic)
        if sub is not None:
            if type_name and normalize_type(type_name) != sub.type:
                raise BridgeError("subscribe: %s has type %s, not %s" % (topic, sub.type, type_name))
            sub.sessions.add(session)
            for message in list(sub.latched.values()):
                self.loop.call_soon(session.deliver, topic, message)
            return sub.type
        existing = self._master_type(topic)
        if type_name:
            type_name, cls = self._message_class(type_name)
            if existing and existing not in (type_name, "*"):
                raise BridgeError("subscribe: %s has type %s, not %s" % (topic, existing, type_name))
        else:
            if not existing or existing == "*":
                raise BridgeError("subscribe: cannot infer the type of %s (it does not exist yet; give 'type')" % topic)
            type_name, cls = self._message_class(existing)
        sub = _Sub(topic, type_name, cls)
        sub.sessions.add(session)
        self.subs[topic] = sub
        # queue_size=None: rospy hands over everything one socket read holds (bounded by
        # buff_size); a slow WebSocket client is bounded later, in its own OutQueue.
        # buff_size is rospy's recv() size: each recv allocates that much, and 1 MiB cost
        # ~0.1 ms per message (mmap/munmap) here, so small reads; big messages take several.
        sub.subscriber = rospy.Subscriber(
            topic, cls, self._on_message, callback_args=sub, queue_size=None, buff_size=_RECV_SIZE, tcp_nodelay=True
        )
        if self.direct_reads:
            self._hook_connections(sub.subscriber.impl, topic)
        return type_name

    def unsubscribe(self, session: Any, topic: str) -> None:
        """Remove session; unregister the rospy.Subscriber when nobody is left."""
        sub = self.subs.get(topic)
        if sub is None:
            return
        sub.sessions.discard(session)
        if not sub.sessions:
            del self.subs[topic]
            sub.subscriber.unregister()

    def begin_batch(self) -> None:
        """Loop thread: hold publishes until :meth:`end_batch` (one send per ROS peer)."""
        self._cork_depth += 1
        self._cork.thread = threading.get_ident()

    def end_batch(self) -> None:
        """Loop thread: send the publishes held since :meth:`begin_batch`."""
        self._cork_depth -= 1
        if self._cork_depth > 0:
            return
        self._cork_depth = 0
        self._cork.thread = None
        pending, self._cork.pending = self._cork.pending, []
        for conn in pending:
            conn.uncork()

    def stats(self) -> dict:
        """Counters of the receive paths (for the node's ``~stats`` service)."""
        stats = dict(self.counters)
        stats["direct_reads"] = self.direct_reads
        stats["direct_read_open"] = len(self._readers)
        return stats

    # ------------------------------------------------------------ direct reads (event loop)

    def _hook_connections(self, impl: Any, topic: str) -> None:
        """Make each new TCPROS connection of impl offer itself to the loop after its handshake.

        rospy calls ``add_connection`` before the connection's thread starts; that thread
        does the handshake and then calls ``conn.receive_loop``, which is replaced here.
        """
        if getattr(impl, "_rbd_direct_reads", False):
            return
        original = impl.add_connection

        def add_connection(conn: Any) -> Any:
            try:
                conn.receive_loop = functools.partial(self._receive_loop, conn, topic)
            except Exception:  # not a TCPROSTransport: rospy's path
                pass
            return original(conn)

        impl.add_connection = add_connection
        impl._rbd_direct_reads = True

    def _receive_loop(self, conn: Any, topic: str, msgs_callback: Any) -> None:
        """Rospy thread, after the handshake: hand the socket to the loop, else read as rospy."""
        if self._offer(conn, topic):
            return  # the loop reads it now; this thread ends
        self.counters["direct_read_fallbacks"] += 1
        _log.warning("topic %s: reading the connection from %s with rospy's thread", topic, conn.endpoint_id)
        TCPROSTransport.receive_loop(conn, msgs_callback)

    def _offer(self, conn: Any, topic: str) -> bool:
        """Rospy thread: ask the loop to adopt conn; True once it did (never both paths)."""
        lock = threading.Lock()
        done = threading.Event()
        state = [None]  # None: undecided, True: the loop reads it, False: rospy does

        def adopt() -> None:
            with lock:
                if state[0] is None:
                    try:
                        self._adopt(conn, topic)
                        state[0] = True
                    except Exception as exc:
                        _log.warning("topic %s: direct read of %s failed: %s", topic, conn.endpoint_id, exc)
                        state[0] = False
            done.set()

        try:
            self.loop.call_soon_threadsafe(adopt)
        except RuntimeError:  # loop closed
            return False
        done.wait(_ADOPT_TIMEOUT)
        with lock:
            if state[0] is None:
                state[0] = False
            return state[0]

    def _adopt(self, conn: Any, topic: str) -> None:
        """Loop thread: start reading conn's socket here (raises if it cannot)."""
        if self.fail_direct_reads:
            raise RuntimeError("direct reads made to fail (~test_fail_direct_reads)")
        if conn.done or conn.socket is None or conn.header is None:
            raise RuntimeError("connection not established")
        buff = conn.read_buff
        leftover = buff.getvalue()[: buff.tell()] if buff is not None else b""
        # our own descriptor: rospy may close its socket object at any time (unsubscribe,
        # shutdown); its shutdown() then ends this stream too, as EOF
        sock = conn.socket.dup()
        reader = LoopReader(
            self.loop,
            sock,
            functools.partial(self._on_payloads, conn, topic),
            functools.partial(self._on_reader_closed, conn, topic),
        )
        try:
            reader.start()
        except Exception:
            sock.close()
            raise
        if buff is not None:
            buff.seek(0)
            buff.truncate()
        self._readers[conn] = reader
        self.counters["direct_read_connections"] += 1
        if leftover:
            reader.feed(leftover)

    def _on_reader_closed(self, conn: Any, topic: str, error: Any) -> None:
        """Loop thread: the stream ended; close rospy's side as its receive loop would."""
        self._readers.pop(conn, None)
        if error is not None:
            _log.info("topic %s: connection from %s ended: %s", topic, conn.endpoint_id, error)
        if not conn.done:
            try:
                conn.close()
            except Exception:
                _log.exception("topic %s: closing the connection from %s failed", topic, conn.endpoint_id)

    def _on_payloads(self, conn: Any, topic: str, payloads: Any) -> None:
        """Loop thread: wrap received messages and deliver them to the subscribed sessions."""
        sub = self.subs.get(topic)
        if sub is None or conn.done:
            return
        self.counters["direct_read_messages"] += len(payloads)
        conn.stat_num_msg += len(payloads)
        conn.stat_bytes += sum(len(p) + 4 for p in payloads)
        header = conn.header or {}
        latched = header.get("latching") == "1"
        stamp = rospy.get_rostime()
        secs, nsecs = stamp.secs, stamp.nsecs
        sessions = list(sub.sessions)
        wanted = set()
        for session in sessions:
            state = session.subs.get(topic)
            if state is not None:
                wanted.add("none" if state.compression == "png" else state.compression)
        batch = len(payloads) > 1
        if batch:  # a burst: queue it all, then one write per client
            for session in sessions:
                session.out.hold()
        try:
            self._deliver_payloads(conn, sub, payloads, sessions, wanted, latched, header, secs, nsecs, batch)
        finally:
            if batch:
                for session in sessions:
                    session.out.release()

    def _deliver_payloads(
        self,
        conn: Any,
        sub: Any,
        payloads: Any,
        sessions: Any,
        wanted: Any,
        latched: bool,
        header: Any,
        secs: int,
        nsecs: int,
        batch: bool,
    ) -> None:
        topic = sub.topic
        cls = sub.cls
        for payload in payloads:
            lazy = _LazyMessage(cls, payload)
            message = TopicMessage(topic, lazy.to_dict, lambda p=payload: (p, secs, nsecs), latched)
            try:
                for compression in wanted:
                    message.frame(compression)
            except Exception as exc:
                _log.error("topic %s: cannot decode or encode a message from %s: %s", topic, conn.endpoint_id, exc)
                continue
            if latched:
                sub.latched[header.get("callerid", "")] = message
            for session in sessions:
                if session not in sub.sessions:
                    continue
                try:
                    # an idle client gets the cached wire frame at once (as from the ROS
                    # threads); latched ones go through deliver, after a queued latched copy
                    compression = None if latched or batch else session.direct_compression(topic)
                    if compression is None or not session.direct(message, compression):
                        session.deliver(topic, message)
                except Exception:
                    _log.exception("delivery to client %s failed", session.client_id)

    # ------------------------------------------------------------ rospy receive threads

    def _on_message(self, msg: Any, sub: Any) -> None:
        """Rospy thread: wrap the message, pre-encode what subscribers want, hop to the loop."""
        self.counters["rospy_read_messages"] += 1
        header = getattr(msg, "_connection_header", None) or {}
        latched = header.get("latching") == "1"
        stamp = rospy.get_rostime()

        def raw() -> Any:
            buff = io.BytesIO()
            msg.serialize(buff)
            return buff.getvalue(), stamp.secs, stamp.nsecs

        message = TopicMessage(sub.topic, lambda binary: msg_to_dict(msg, binary), raw, latched)
        sessions = list(sub.sessions)
        wanted = set()
        for session in sessions:
            state = session.subs.get(sub.topic)
            if state is not None:
                wanted.add("none" if state.compression == "png" else state.compression)
        try:
            for compression in wanted:
                message.frame(compression)
        except Exception:
            _log.exception("cannot encode a message of %s", sub.topic)
            return
        if latched:
            sub.latched[header.get("callerid", "")] = message
        now = time.monotonic()
        burst = now - sub.last_rx < _BURST_GAP
        sub.last_rx = now
        rest = None
        with self._inbox_lock:
            if not burst and not self._inbox and not self._draining and not latched:
                # nothing older is on its way: send straight to clients whose queue is
                # empty (no hop to the event loop); the others get it through the loop
                rest = []
                for session in sessions:
                    compression = session.direct_compression(sub.topic)
                    if compression is None or not self._send_direct(session, message, compression):
                        rest.append(session)
                if not rest:
                    return
            wake = not self._inbox
            self._inbox.append((sub, message, rest))
        if wake:  # one loop wake-up per burst, not per message
            try:
                self.loop.call_soon_threadsafe(self._drain_inbox)
            except RuntimeError:  # loop closed: shutting down
                pass

    @staticmethod
    def _send_direct(session: Any, message: Any, compression: str) -> bool:
        try:
            return session.direct(message, compression)
        except Exception:
            _log.exception("direct send to client %s failed", session.client_id)
            return False

    def _drain_inbox(self) -> None:
        while True:
            with self._inbox_lock:
                if not self._inbox:
                    self._draining = False
                    return
                items = list(self._inbox)
                self._inbox.clear()
                self._draining = True  # no direct sends may overtake these
            for sub, message, only in items:
                self._fan_out(sub, message, only)

    @staticmethod
    def _fan_out(sub: Any, message: Any, only: Any = None) -> None:
        for session in list(sub.sessions) if only is None else only:
            if session not in sub.sessions:
                continue
            try:
                session.deliver(sub.topic, message)
            except Exception:
                _log.exception("delivery to client %s failed", session.client_id)

    # ------------------------------------------------------------ service calls

    def call_service(
        self, session: Any, service: str, args: Any, timeout: Optional[float], done: Callable[..., Any]
    ) -> None:
        """Run the call in the pool; done(ok, values) is called on the loop (at most once)."""
        state = {"done": False}

        def finish(ok: bool, values: Any) -> None:
            if not state["done"]:
                state["done"] = True
                done(ok, values)

        if timeout is None and self.call_timeout > 0:
            timeout = self.call_timeout
        handle = None
        if timeout:
            handle = self.loop.call_later(
                timeout, finish, False, "service %s: no response within %.1f s" % (service, timeout)
            )

        def work() -> None:
            try:
                if RosApi.handles(service):
                    result = (True, self.rosapi.call(service, args))
                else:
                    result = (True, self._call_ros(service, args))
            except (RosApiError, BridgeError, ConversionError) as exc:
                result = (False, str(exc))
            except Exception as exc:  # rospy raises a zoo of types
                result = (False, "service %s failed: %s" % (service, exc))
            self.loop.call_soon_threadsafe(complete, result)

        def complete(result: Any) -> None:
            if handle is not None:
                handle.cancel()
            finish(*result)

        self.pool.submit(work)

    def _lookup_service_type(self, service: str) -> Any:
        type_name = self._srv_types.get(service)
        if type_name is None:
            hosted = self.hosted.get(service)
            if hosted is not None:
                type_name = hosted.type
            else:
                type_name = rosservice.get_service_type(service)
            if not type_name:
                raise BridgeError("service %s does not exist" % service)
            self._srv_types[service] = type_name
        return type_name

    def _request(self, service: str, cls: Any, args: Any) -> Any:
        req_cls = cls._request_class
        if isinstance(args, list):
            if len(args) > len(req_cls.__slots__):
                raise BridgeError(
                    "service %s: %d arguments given, request has %d fields"
                    % (service, len(args), len(req_cls.__slots__))
                )
            args = dict(zip(req_cls.__slots__, args))
        try:
            request, _ = dict_to_msg(req_cls, args, rospy.Time.now)
        except ConversionError as exc:
            raise BridgeError("service %s: %s" % (service, exc)) from None
        return request

    def _call_ros(self, service: str, args: Any) -> Any:
        try:
            type_name = self._lookup_service_type(service)
        except rosservice.ROSServiceIOException as exc:
            raise BridgeError("service %s: %s" % (service, exc)) from None
        cls = get_service_class(type_name)
        request = self._request(service, cls, args)
        with self._proxy_lock:
            entry = self._proxies.get(service)
            if entry is None or entry[0] != type_name:
                entry = (type_name, rospy.ServiceProxy(service, cls, persistent=True), threading.Lock())
                self._proxies[service] = entry
                fresh = True
            else:
                fresh = False
        _, proxy, lock = entry
        if not lock.acquire(False):
            # a call on the persistent connection is in flight: use a one-shot connection
            return msg_to_dict(rospy.ServiceProxy(service, cls).call(request))
        try:
            try:
                response = proxy.call(request)
            except Exception as exc:
                self._drop_proxy(service, entry)
                if fresh or not _is_transport_error(exc):
                    raise
                # the provider restarted since the connection was made: retry once on a new one
                self._srv_types.pop(service, None)
                response = rospy.ServiceProxy(service, cls).call(request)
        finally:
            lock.release()
        return msg_to_dict(response)

    def _drop_proxy(self, service: str, entry: Any) -> None:
        with self._proxy_lock:
            if self._proxies.get(service) is entry:
                del self._proxies[service]
        self._srv_types.pop(service, None)
        try:
            entry[1].close()
        except Exception:
            pass

    # ------------------------------------------------------------ client-hosted services

    def advertise_service(self, session: Any, service: str, type_name: str) -> None:
        """Serve service in ROS on behalf of session."""
        try:
            type_name = normalize_type(type_name)
            cls = get_service_class(type_name)
        except ConversionError as exc:
            raise BridgeError(str(exc)) from None
        hosted = self.hosted.get(service)
        if hosted is not None:
            if hosted.session is not session:
                raise BridgeError("advertise_service: %s is already provided by another client" % service)
            self._unhost(hosted, "re-advertised")
        else:
            try:
                uri = self.master.lookupService(service)
            except Exception:
                uri = None
            if uri:
                raise BridgeError("advertise_service: %s is already provided in ROS (%s)" % (service, uri))
        hosted = _Hosted(self, service, type_name, cls, session)
        hosted.server = rospy.Service(service, cls, hosted.handle)
        self.hosted[service] = hosted
        self._srv_types.pop(service, None)

    def _unhost(self, hosted: Any, reason: str) -> None:
        if self.hosted.get(hosted.name) is hosted:
            del self.hosted[hosted.name]
        self._srv_types.pop(hosted.name, None)
        hosted.close(reason)

    def unadvertise_service(self, session: Any, service: str) -> None:
        """Stop serving service for session."""
        hosted = self.hosted.get(service)
        if hosted is not None and hosted.session is session:
            self._unhost(hosted, "unadvertised by its WebSocket provider")

    def service_response(self, session: Any, service: str, call_id: Any, values: Any, ok: bool) -> None:
        """Pass a client's answer to the waiting ROS caller."""
        hosted = self.hosted.get(service)
        if hosted is None or hosted.session is not session:
            raise BridgeError("service_response: %s is not advertised by this client" % service)
        if not hosted.answer(call_id, ok, values):
            raise BridgeError("service_response: no pending call %r" % (call_id,), "warning")

    # ------------------------------------------------------------ teardown

    def session_closed(self, session: Any) -> None:
        """Release publishers, subscriptions and hosted services of a gone client."""
        for topic in list(session.advertised):
            self.unadvertise(session, topic)
        for topic, sub in list(self.subs.items()):
            if session in sub.sessions:
                self.unsubscribe(session, topic)
        for hosted in list(self.hosted.values()):
            if hosted.session is session:
                self._unhost(hosted, "its WebSocket provider disconnected")

    def shutdown(self) -> None:
        """Stop everything (node exit)."""
        for reader in list(self._readers.values()):
            reader.stop()
        for hosted in list(self.hosted.values()):
            self._unhost(hosted, "bridge shutting down")
        self.pool.shutdown(wait=False)

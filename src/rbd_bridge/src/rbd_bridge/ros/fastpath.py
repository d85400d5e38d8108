"""Opt-in patches of rospy internals that make the bridge faster (``~rospy_fast_path``, default on).

Everything the bridge does to rospy's private parts is here, behind one switch (README,
Design): publisher connections that never block (:class:`_DirectConnection`), subscribed
connections read by the event loop after rospy's handshake (``~direct_reads``).
"""

import collections
import concurrent.futures
import contextlib
import functools
import inspect
import logging
import socket
import threading
import types
import warnings
from typing import Any, Callable

import rospy
from rospy.exceptions import TransportTerminated
from rospy.impl.tcpros_base import TCPROSTransport

from rbd_bridge.core.fanout import TopicMessage, deliver, prepare, send_direct
from rbd_bridge.core.tcpros import LoopReader
from rbd_bridge.ros.msgconv import msg_to_dict

__all__ = ["FastPath", "rospy_unfit"]

_log = logging.getLogger("rbd_bridge")
_ADOPT_TIMEOUT = 5.0  # a ROS thread waits this long for the loop to take a connection [s]
# A corked write holds at most min(queue_size, this) publishes (rospy keeps only the newest
# queue_size of each socket read; README, Design: Bursts); the rest are written one by one
_CORK_MESSAGES = 256


def rospy_unfit() -> str:
    """'' if rospy's internals are those this module was written for, else what differs (checked at start)."""
    try:  # the methods replaced or called (by arity) and the attributes of a connection that are read
        from rospy.topics import _PublisherImpl, _SubscriberImpl

        conn = TCPROSTransport(types.SimpleNamespace(direction=None), "rbd_bridge_probe")
        methods = (conn.receive_loop, conn.set_cleanup_callback, _PublisherImpl.add_connection)
        arity = [len(inspect.signature(m).parameters) for m in methods + (_SubscriberImpl.add_connection,)]
        attrs = ("done", "socket", "header", "read_buff", "endpoint_id", "stat_bytes", "stat_num_msg", "close")
        missing = [name for name in attrs if not hasattr(conn, name)]
    except Exception as exc:  # whatever another rospy raises here
        return "%s: %s" % (type(exc).__name__, exc)
    return "" if arity == [1, 1, 2, 2] and not missing else "arities %s, missing %s" % (arity, missing)


class _DirectConnection:
    """A rospy publisher connection that writes at once when it can, never blocking the caller.

    A stuck subscriber never blocks the event loop, costs at most ``queue_size`` messages
    (its backlog, written in order by this connection's own thread) and never delays the
    other subscribers.
    """

    def __init__(self, connection: Any, queue_size: int, cork: Any = None) -> None:
        self._connection, self._cork = connection, cork
        self._parts = None  # writes held by the cork (False: write through until uncork)
        self._queue_size = max(1, queue_size)
        self._cork_limit = min(self._queue_size, _CORK_MESSAGES)
        self._lock = threading.RLock()  # conn.close() calls _closed with it held
        self._wake = threading.Condition(self._lock)
        self._backlog, self._busy, self._thread, self.dropped = collections.deque(), False, None, 0
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

        While the cork is set by the calling thread, data is held until :meth:`uncork`; once
        the held messages reach the limit they leave together and the rest of the batch is
        written one by one.
        """
        cork = self._cork
        if cork is not None and cork.thread == threading.get_ident():
            with self._lock:
                if self._connection.done:
                    raise TransportTerminated("connection closed")
                parts = self._parts
                if parts is None:
                    self._parts = [data]
                    cork.pending.append(self)
                    return True
                if parts is not False:
                    if len(parts) < self._cork_limit:
                        parts.append(data)
                        return True
                    self._parts = False  # the limit: what is held leaves now, the rest writes through
                    self._write(b"".join(parts))
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
            if conn.done:  # (also after the writer thread's error: it closes conn)
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
                del self._backlog[1]  # the oldest whole message (never the partly sent head)
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
            except Exception:
                with self._lock:
                    self._backlog.clear()
                with contextlib.suppress(Exception):
                    conn.close()
                return


def _lazy_dict(cls: Any, payload: bytes) -> Callable[[bool], Any]:
    """to_dict of a received message that stays serialized until a client needs a dict."""
    kept = []

    def to_dict(binary: bool) -> Any:
        if not kept:
            kept.append(cls().deserialize(payload))
        return msg_to_dict(kept[0], binary)

    return to_dict


class FastPath:
    """The patches, for :class:`rbd_bridge.ros.topics.Topics` and the backend.

    Args:
        loop: The event loop.
        lookup: ``lookup(topic)`` -> the current subscription of topic (or None).
        direct_reads: Read subscribed connections in the event loop.
        fail_direct_reads: Test hook: every take-over fails (rospy's threads read).
    """

    COUNTERS = ("direct_read_connections", "direct_read_messages", "direct_read_fallbacks")

    def __init__(self, loop: Any, lookup: Callable[[str], Any], direct_reads: bool = True, fail: bool = False) -> None:
        """Nothing patched until publishers and subscribers are made through it."""
        self.loop, self.lookup, self.direct_reads, self.fail_direct_reads = loop, lookup, direct_reads, fail
        self._cork = types.SimpleNamespace(thread=None, pending=[])  # whose writes are held; who holds some
        self._readers = {}  # rospy connection -> LoopReader (loop thread only)
        self.counters = collections.Counter(dict.fromkeys(self.COUNTERS, 0))

    def publisher(self, topic: str, cls: Any, queue_size: int, latch: bool, listener: Any, window: Any) -> Any:
        """A rospy.Publisher whose connections are :class:`_DirectConnection` s.

        Adding a connection and replaying the advertise window to it happen under the
        window's lock, which publishes take too: nothing is lost, doubled or reordered.
        """
        with warnings.catch_warnings():  # queue_size=None is deliberate: the queue is ours
            warnings.simplefilter("ignore")
            publisher = rospy.Publisher(topic, cls, queue_size=None, latch=latch, subscriber_listener=listener)
        impl = publisher.impl
        if not getattr(impl, "_rbd_direct", False):  # one impl per topic in this process
            cork, original = self._cork, impl.add_connection

            def add_connection(connection: Any) -> Any:
                with window.lock:
                    return original(_DirectConnection(connection, queue_size, cork))

            impl.add_connection = add_connection
            impl._rbd_direct = True
        return publisher

    def begin_batch(self) -> None:
        """Loop thread: hold publishes until :meth:`end_batch` (one send per ROS peer)."""
        self._cork.thread = threading.get_ident()

    def end_batch(self) -> None:
        """Loop thread: send the publishes held since :meth:`begin_batch`."""
        self._cork.thread = None
        pending, self._cork.pending = self._cork.pending, []
        for conn in pending:
            conn.uncork()

    def stats(self) -> dict:
        """Counters of the direct reads (for the node's ``~stats``)."""
        return dict(self.counters, direct_read_open=len(self._readers))

    def shutdown(self) -> None:
        """Stop every direct reader."""
        for reader in list(self._readers.values()):
            reader.stop()

    def read_directly(self, sub: Any) -> None:
        """Make each new TCPROS connection of sub's subscriber offer itself to the loop.

        rospy calls ``add_connection`` before the connection's thread starts; that thread
        does the handshake and then calls ``conn.receive_loop``, which is replaced here.
        """
        if not self.direct_reads:
            return
        impl = sub.subscriber.impl
        topic = sub.topic
        if getattr(impl, "_rbd_direct_reads", False):
            return
        original = impl.add_connection

        def add_connection(conn: Any) -> Any:
            conn.receive_loop = functools.partial(self._receive_loop, conn, topic)
            return original(conn)

        impl.add_connection = add_connection
        impl._rbd_direct_reads = True

    def _receive_loop(self, conn: Any, topic: str, msgs_callback: Any) -> None:
        """Rospy thread, after the handshake: the loop adopts conn, else rospy's loop reads it (never both)."""
        decided = concurrent.futures.Future()

        def adopt() -> None:
            if decided.set_running_or_notify_cancel():  # False: the thread stopped waiting
                try:
                    self._adopt(conn, topic)
                    decided.set_result(True)
                except Exception as exc:
                    _log.warning("topic %s: direct read of %s failed: %s", topic, conn.endpoint_id, exc)
                    decided.set_result(False)

        try:
            self.loop.call_soon_threadsafe(adopt)
            if decided.result(_ADOPT_TIMEOUT):
                return  # the loop reads it now; this thread ends
        except RuntimeError:  # loop closed
            pass
        except concurrent.futures.TimeoutError:  # no cancel once the loop is adopting it: its answer counts
            if not decided.cancel() and decided.result():
                return
        self.counters["direct_read_fallbacks"] += 1
        _log.warning("topic %s: reading the connection from %s with rospy's thread", topic, conn.endpoint_id)
        TCPROSTransport.receive_loop(conn, msgs_callback)

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
        sub = self.lookup(topic)
        if sub is None or conn.done:
            return
        self.counters["direct_read_messages"] += len(payloads)
        conn.stat_num_msg += len(payloads)
        conn.stat_bytes += sum(len(p) + 4 for p in payloads)
        header = conn.header or {}
        latched = header.get("latching") == "1"
        now = rospy.get_rostime()
        stamp = (now.secs, now.nsecs)
        sessions = list(sub.sessions)
        batch = len(payloads) > 1
        if batch:  # a burst: queue it all, then one write per client
            for session in sessions:
                session.out.hold()
        try:
            for payload in payloads:
                message = TopicMessage(topic, _lazy_dict(sub.cls, payload), lambda p=payload: (p,) + stamp, latched)
                if not prepare(message, sessions):
                    continue
                if latched:
                    sub.latched[header.get("callerid", "")] = message
                # idle clients get the framed message at once (latched ones go through deliver,
                # after a queued latched copy; a burst is queued whole, then one write per client)
                deliver(message, sessions if latched or batch else send_direct(message, sessions), sub.sessions)
        finally:
            if batch:
                for session in sessions:
                    session.out.release()

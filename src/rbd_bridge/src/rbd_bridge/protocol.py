"""rosbridge v2 protocol session: parse, check, dispatch, merge subscriptions, queue output.

ROS-free and transport-free. A :class:`Session` is driven from one thread (the server's
event loop): ``receive()`` takes client frames, a *backend* (ROS side, see
:class:`Backend`) does the ROS work, and frames for the client go into a bounded
:class:`OutQueue` that the transport drains.
"""

import collections
import itertools
import json
import logging
import time
from typing import Any, Callable, Dict, NoReturn, Optional

from rbd_bridge import encoding
from rbd_bridge.msgconv import ConversionError, normalize_type
from rbd_bridge.security import AuthError, check_mac

__all__ = ["BridgeError", "Backend", "OutQueue", "Session", "TopicMessage", "LEVELS", "COMPRESSIONS"]

LEVELS = {"none": 0, "error": 1, "warning": 2, "info": 3}
COMPRESSIONS = ("none", "png", "cbor", "cbor-raw")
_MAX_FRAGMENT_SETS = 32
_FRAGMENT_TTL = 30.0
_MAX_FRAGMENTS = 100000

_log = logging.getLogger("rbd_bridge")


class BridgeError(Exception):
    """An op that cannot be done; sent to the client as a status (when it opted in)."""

    def __init__(self, text: str, level: str = "error") -> None:
        """Keep the status level with the text."""
        super().__init__(text)
        self.level = level


class Backend:
    """The ROS side a Session talks to (all methods are called on the session's thread)."""

    def advertise(self, session: Any, topic: str, type_name: str, latch: bool, queue_size: int) -> NoReturn:
        """Register session as a publisher of topic."""
        raise NotImplementedError

    def unadvertise(self, session: Any, topic: str) -> NoReturn:
        """Drop session's publisher registration for topic."""
        raise NotImplementedError

    def publish(self, session: Any, topic: str, msg: Any) -> NoReturn:
        """Publish msg (a dict) on topic; return the list of fields filled with defaults."""
        raise NotImplementedError

    def subscribe(self, session: Any, topic: str, type_name: str) -> NoReturn:
        """Start delivering topic to session (``session.deliver``); return the resolved type."""
        raise NotImplementedError

    def unsubscribe(self, session: Any, topic: str) -> NoReturn:
        """Stop delivering topic to session."""
        raise NotImplementedError

    def call_service(
        self, session: Any, service: str, args: Any, timeout: Optional[float], done: Callable[..., Any]
    ) -> NoReturn:
        """Call service; later invoke ``done(ok, values)`` on the session's thread."""
        raise NotImplementedError

    def advertise_service(self, session: Any, service: str, type_name: str) -> NoReturn:
        """Host service in ROS, forwarding requests to session (``session.send_service_request``)."""
        raise NotImplementedError

    def unadvertise_service(self, session: Any, service: str) -> NoReturn:
        """Stop hosting service for session."""
        raise NotImplementedError

    def service_response(self, session: Any, service: str, call_id: Any, values: Any, ok: bool) -> NoReturn:
        """Answer a request previously forwarded to session."""
        raise NotImplementedError

    def begin_batch(self) -> None:
        """Frames of one network read follow (the backend may hold its writes until end_batch)."""

    def end_batch(self) -> None:
        """The read's frames are handled: send what begin_batch held."""

    def session_closed(self, session: Any) -> NoReturn:
        """Release everything session held."""
        raise NotImplementedError


class TopicMessage:
    """One ROS message on its way to clients, encoded at most once per compression.

    Args:
        topic: Topic name.
        to_dict: Callable(binary) returning the message as a JSON-ready dict
            (binary=True for CBOR).
        raw: Callable returning (serialized bytes, secs, nsecs) for ``cbor-raw``.
    """

    __slots__ = ("topic", "_to_dict", "_raw", "_frames", "latched", "wire")

    def __init__(
        self, topic: str, to_dict: Callable[..., Any], raw: Callable[..., Any] = None, latched: Any = False
    ) -> None:
        """Wrap one message."""
        self.topic = topic
        self._to_dict = to_dict
        self._raw = raw
        self._frames = {}
        self.latched = latched
        self.wire = {}  # the transport's ready-to-send bytes per compression (its cache)

    def frame(self, compression: str) -> Any:
        """Return the whole ``publish`` frame (str for none/png, bytes for cbor*)."""
        frame = self._frames.get(compression)
        if frame is None:
            frame = self._encode(compression)
            self._frames[compression] = frame
        return frame

    def _encode(self, compression: str) -> Any:
        if compression == "none":
            return '{"op":"publish","topic":%s,"msg":%s}' % (
                json.dumps(self.topic),
                encoding.json_dumps(self._to_dict(False)),
            )
        if compression == "png":
            return encoding.json_dumps({"op": "png", "data": encoding.png_encode(self.frame("none"))})
        if compression == "cbor":
            return encoding.cbor_dumps({"op": "publish", "topic": self.topic, "msg": self._to_dict(True)})
        if compression == "cbor-raw":
            data, secs, nsecs = self._raw()
            return encoding.cbor_dumps(
                {"op": "publish", "topic": self.topic, "msg": {"secs": secs, "nsecs": nsecs, "bytes": data}}
            )
        raise ValueError(compression)


class OutQueue:
    """Bounded FIFO of frames for one client.

    Over ``max_frames`` or ``max_bytes`` the oldest frames are dropped (a stalled client
    costs bounded memory and never delays others). A topic frame may also carry a
    per-topic limit (the subscription's ``queue_length``): then only the newest frames of
    that topic are kept.
    """

    def __init__(
        self, max_frames: int = 1000, max_bytes: int = 16 * 1024 * 1024, notify: Callable[..., Any] = None
    ) -> None:
        """Create an empty queue; notify() is called when a frame arrives in an empty queue."""
        self.max_frames = max_frames
        self.max_bytes = max_bytes
        self.notify = notify
        self._queue = collections.deque()
        self._per_topic = {}
        self.bytes = 0
        self.frames = 0
        self.dropped = 0
        self.held = 0

    def __len__(self) -> int:
        """Number of live frames."""
        return self.frames

    def push(self, frame: Dict[str, Any], topic: str = None, topic_limit: int = 0) -> None:
        """Append frame; drop old frames to respect the bounds."""
        entry = [frame, topic, True]
        was_empty = self.frames == 0
        self._queue.append(entry)
        self.frames += 1
        self.bytes += len(frame)
        if topic is not None:
            per = self._per_topic.get(topic)
            if per is None:
                per = self._per_topic[topic] = collections.deque()
            per.append(entry)
            if topic_limit > 0:
                while len(per) > topic_limit:
                    self._kill(per.popleft())
        while self.frames > self.max_frames or (self.bytes > self.max_bytes and self.frames > 1):
            self._drop_oldest()
        if was_empty and self.notify is not None and not self.held:
            self.notify()

    def hold(self) -> None:
        """Collect pushes without notifying (a batch), until the matching :meth:`release`."""
        self.held += 1

    def release(self) -> None:
        """End a :meth:`hold`; notify once if frames are waiting."""
        self.held -= 1
        if not self.held and self.frames and self.notify is not None:
            self.notify()

    def _kill(self, entry: Any) -> None:
        if entry[2]:
            entry[2] = False
            self.frames -= 1
            self.bytes -= len(entry[0])
            self.dropped += 1
            entry[0] = None

    def _drop_oldest(self) -> None:
        while self._queue:
            entry = self._queue.popleft()
            if entry[2]:
                self._forget(entry)
                self._kill(entry)
                return

    def _forget(self, entry: Any) -> None:
        topic = entry[1]
        if topic is not None:
            per = self._per_topic.get(topic)
            if per:
                while per and not per[0][2]:
                    per.popleft()
                if per and per[0] is entry:
                    per.popleft()
                if not per:
                    del self._per_topic[topic]

    def pop(self) -> Any:
        """Return the oldest live frame, or None when empty."""
        while self._queue:
            entry = self._queue.popleft()
            if entry[2]:
                self._forget(entry)
                entry[2] = False
                self.frames -= 1
                self.bytes -= len(entry[0])
                return entry[0]
        return None


class _TopicSub:
    """A client's merged subscriptions to one topic."""

    __slots__ = (
        "topic",
        "type",
        "by_id",
        "throttle",
        "queue_length",
        "fragment_size",
        "compression",
        "last",
        "pending",
        "timer",
    )

    def __init__(self, topic: str, type_name: str) -> None:
        self.topic = topic
        self.type = type_name
        self.by_id = collections.OrderedDict()
        self.throttle = 0.0
        self.queue_length = 0
        self.fragment_size = None
        self.compression = "none"
        self.last = -1e18
        self.pending = collections.deque()
        self.timer = None

    def merge(self) -> None:
        opts = list(self.by_id.values())
        self.throttle = min(o["throttle_rate"] for o in opts) / 1000.0
        self.queue_length = max(o["queue_length"] for o in opts)
        sizes = [o["fragment_size"] for o in opts if o["fragment_size"]]
        self.fragment_size = min(sizes) if sizes else None
        self.compression = opts[-1]["compression"]
        if self.queue_length > 0:
            while len(self.pending) > self.queue_length:
                self.pending.popleft()
        else:
            self.pending.clear()


def _get(frame: Dict[str, Any], key: str, kinds: Any, default: Any = None, required: Any = False) -> Any:
    value = frame.get(key, default)
    if value is None:
        if required:
            raise BridgeError("%s: missing field %r" % (frame.get("op"), key))
        return default
    if isinstance(value, bool) and bool not in kinds:
        raise BridgeError("%s: field %r has the wrong type" % (frame.get("op"), key))
    if not isinstance(value, kinds):
        raise BridgeError("%s: field %r has the wrong type" % (frame.get("op"), key))
    return value


def _name(frame: Dict[str, Any], key: str) -> Any:
    value = _get(frame, key, (str,), required=True)
    if not value or len(value) > 1024 or any(c.isspace() for c in value):
        raise BridgeError("%s: invalid %s name %r" % (frame.get("op"), key, value[:80]))
    return value if value.startswith("/") else "/" + value


def _nonneg_int(frame: Dict[str, Any], key: str) -> Any:
    value = _get(frame, key, (int, float), default=0)
    if value != value or value < 0:
        raise BridgeError("%s: %r must be >= 0" % (frame.get("op"), key))
    return value


class Session:
    """One WebSocket client speaking rosbridge v2.

    Args:
        client_id: Unique id of this connection (int).
        backend: The :class:`Backend`.
        policy: :class:`rbd_bridge.security.Policy`.
        out: :class:`OutQueue` for frames to the client.
        call_later: ``call_later(delay_s, fn)`` returning a handle with ``cancel()``.
        close: Callable(code, reason) closing the connection.
        peer: Client address text (logs only).
        clock: Monotonic clock (throttling, fragment expiry).
        wall: Wall clock in seconds (auth time window).
    """

    def __init__(
        self,
        client_id: int,
        backend: Any,
        policy: Any,
        out: Any,
        call_later: Callable[..., Any],
        close: Callable[..., Any] = None,
        peer: str = "?",
        clock: Callable[..., Any] = time.monotonic,
        wall: Callable[..., Any] = time.time,
    ) -> None:
        """Create a session; nothing is sent until the client asks."""
        self.client_id = client_id
        self.backend = backend
        self.policy = policy
        self.out = out
        self.call_later = call_later
        self.close_cb = close
        self.peer = peer
        self.clock = clock
        self.wall = wall
        self.level = 0
        self.authenticated = not policy.authenticate
        self.closed = False
        self.subs = {}
        self.advertised = set()
        self.services = set()
        self._fragments = collections.OrderedDict()
        self._ids = itertools.count(1)
        self.received = 0
        self.errors = 0
        self.max_message_size = None
        # set by a transport that can send a frame at once from another thread:
        # direct(message, compression) -> True if it took the frame (see direct_compression)
        self.direct = None
        self._rejected = 0
        self._rejected_logged = -1e18
        self._handlers = {
            "fragment": self._op_fragment,
            "set_level": self._op_set_level,
            "auth": self._op_auth,
            "advertise": self._op_advertise,
            "unadvertise": self._op_unadvertise,
            "publish": self._op_publish,
            "subscribe": self._op_subscribe,
            "unsubscribe": self._op_unsubscribe,
            "call_service": self._op_call_service,
            "advertise_service": self._op_advertise_service,
            "unadvertise_service": self._op_unadvertise_service,
            "service_response": self._op_service_response,
        }

    # ----------------------------------------------------------------- input

    def receive(self, data: Any, _depth: int = 0) -> None:
        """Handle one frame from the client (str or bytes). Never raises."""
        if self.closed:
            return
        self.received += 1
        frame = None
        try:
            frame = self._decode(data)
            self._dispatch(frame, _depth)
        except BridgeError as exc:
            self.errors += 1
            self._log_rejected(exc)
            # an unknown op or a frame before auth: the status names the frame's id (as rosbridge)
            self.status(exc.level, str(exc), frame.get("id") if frame is not None else None)
        except Exception as exc:  # a bug must not end the session
            self.errors += 1
            _log.exception("client %s: internal error", self.client_id)
            self.status("error", "internal error: %s" % exc)

    def _log_rejected(self, exc: Exception) -> None:
        """Log a rejected frame (at most one line per second per client, with a count)."""
        now = self.clock()
        self._rejected += 1
        if now - self._rejected_logged >= 1.0:
            _log.warning(
                "client %s (%s): frame rejected (%d since last report): %s",
                self.client_id,
                self.peer,
                self._rejected,
                exc,
            )
            self._rejected = 0
            self._rejected_logged = now

    def _decode(self, data: Any) -> Any:
        if isinstance(data, (bytes, bytearray, memoryview)):
            try:
                frame = encoding.cbor_loads(data)
            except (encoding.DecodeError, ValueError, TypeError, OverflowError):
                try:
                    frame = json.loads(bytes(data).decode("utf-8"))
                except (UnicodeDecodeError, ValueError, RecursionError):
                    raise BridgeError("binary frame is neither CBOR nor UTF-8 JSON") from None
        else:
            try:
                frame = json.loads(data)
            except (ValueError, RecursionError) as exc:
                raise BridgeError("malformed JSON: %s" % str(exc)[:120]) from None
        if not isinstance(frame, dict):
            raise BridgeError("a frame must be a JSON object with an 'op' field, got %s" % type(frame).__name__)
        return frame

    def _dispatch(self, frame: Dict[str, Any], depth: int) -> None:
        op = frame.get("op")
        if not isinstance(op, str):
            raise BridgeError("frame without a string 'op' field")
        handler = self._handlers.get(op)
        if handler is None:
            raise BridgeError("unsupported op %r" % op[:40])
        if not self.authenticated and op != "auth":
            # as rosbridge: anything but auth on an unauthenticated connection ends it
            _log.warning("client %s (%s) sent %r before authenticating: closing", self.client_id, self.peer, op[:40])
            if self.close_cb is not None:
                self.close_cb(1008, "authentication required")
            self.close()
            return
        try:
            if op == "fragment":
                handler(frame, depth)
            else:
                handler(frame)
        except BridgeError as exc:
            self.errors += 1
            self._log_rejected(exc)
            self.status(exc.level, str(exc), frame.get("id"))
        except ConversionError as exc:
            self.errors += 1
            self._log_rejected(exc)
            self.status("error", "%s: %s" % (op, exc), frame.get("id"))

    # ----------------------------------------------------------------- output

    def status(self, level: str, text: str, frame_id: Any = None) -> None:
        """Send a status frame if the client asked for this level (set_level)."""
        if self.level == 0 or LEVELS.get(level, 3) > self.level:
            return
        frame = {"op": "status", "level": level, "msg": text}
        if frame_id is not None:
            frame["id"] = frame_id
        self.out.push(encoding.json_dumps(frame))

    def send(self, frame_dict: Any, fragment_size: Optional[int] = None, compression: str = "none") -> None:
        """Queue a control/service frame with optional fragmentation or PNG compression."""
        text = encoding.json_dumps(frame_dict)
        self._push_text(text, fragment_size, compression, None, 0)

    def _push_text(self, text: str, fragment_size: Optional[int], compression: str, topic: str, limit: int) -> None:
        if compression == "png":
            data = encoding.png_encode(text)
            if fragment_size and len(data) > fragment_size:
                frag_id = "png:%d" % next(self._ids)
                total = (len(data) + fragment_size - 1) // fragment_size
                for i in range(total):
                    part = {
                        "op": "png",
                        "id": frag_id,
                        "data": data[i * fragment_size : (i + 1) * fragment_size],
                        "num": i,
                        "total": total,
                    }
                    self.out.push(encoding.json_dumps(part), topic, 0)
                return
            self.out.push(encoding.json_dumps({"op": "png", "data": data}), topic, limit)
            return
        if fragment_size and len(text) > fragment_size:
            for part in encoding.fragment(text, fragment_size, "fragment:%d" % next(self._ids)):
                self.out.push(part, topic, 0)
            return
        self.out.push(text, topic, limit)

    def deliver(self, topic: str, message: Any) -> None:
        """Take one :class:`TopicMessage` of a subscribed topic (applies throttle/queue)."""
        sub = self.subs.get(topic)
        if sub is None or self.closed:
            return
        if sub.throttle <= 0:
            self._emit(sub, message, sub.queue_length)
            return
        now = self.clock()
        if sub.timer is None and now - sub.last >= sub.throttle:
            sub.last = now
            self._emit(sub, message, 0)
            return
        if sub.queue_length <= 0:
            return
        sub.pending.append(message)
        while len(sub.pending) > sub.queue_length:
            sub.pending.popleft()
        if sub.timer is None:
            sub.timer = self.call_later(max(0.0, sub.last + sub.throttle - now), lambda: self._flush(topic))

    def direct_compression(self, topic: str) -> Optional[str]:
        """Compression of topic if a message may bypass :meth:`deliver`, else None.

        True for a subscription without throttle, fragmentation or PNG: then the frame
        :meth:`deliver` would queue is ``message.frame(compression)`` unchanged, and a
        transport whose queue is empty may send it at once (:attr:`direct`). Safe to call
        from another thread (reads only).
        """
        if self.direct is None or self.closed:
            return None
        sub = self.subs.get(topic)
        if sub is None or sub.throttle > 0 or sub.fragment_size or sub.compression == "png":
            return None
        return sub.compression

    def _flush(self, topic: str) -> None:
        sub = self.subs.get(topic)
        if sub is None or self.closed:
            return
        sub.timer = None
        if not sub.pending:
            return
        sub.last = self.clock()
        self._emit(sub, sub.pending.popleft(), 0)
        if sub.pending:
            sub.timer = self.call_later(sub.throttle, lambda: self._flush(topic))

    def _emit(self, sub: Any, message: Any, limit: int) -> None:
        compression = sub.compression
        if compression in ("cbor", "cbor-raw"):
            self.out.push(message.frame(compression), sub.topic, limit)
        elif compression == "png" or sub.fragment_size:
            self._push_text(message.frame("none"), sub.fragment_size, compression, sub.topic, limit)
        else:
            self.out.push(message.frame("none"), sub.topic, limit)

    def send_service_request(self, service: str, call_id: Any, args: Any) -> None:
        """Forward a ROS call of a client-hosted service to the client."""
        self.out.push(encoding.json_dumps({"op": "call_service", "id": call_id, "service": service, "args": args}))

    # ----------------------------------------------------------------- ops

    def _op_fragment(self, frame: Dict[str, Any], depth: int) -> None:
        frag_id = frame.get("id")
        data = frame.get("data")
        num = frame.get("num")
        total = frame.get("total")
        if not isinstance(frag_id, (str, int)) or isinstance(frag_id, bool) or not isinstance(data, str):
            raise BridgeError("fragment: needs a string/int 'id' and a string 'data'")
        if not (isinstance(num, int) and isinstance(total, int)) or isinstance(num, bool) or isinstance(total, bool):
            raise BridgeError("fragment: 'num' and 'total' must be integers")
        if not (0 < total <= _MAX_FRAGMENTS and 0 <= num < total):
            raise BridgeError("fragment: num/total out of range")
        if depth > 1:
            raise BridgeError("fragment: fragments nested too deeply")
        now = self.clock()
        for key in [k for k, v in self._fragments.items() if now - v["t"] > _FRAGMENT_TTL]:
            del self._fragments[key]
        entry = self._fragments.get(frag_id)
        if entry is None or entry["total"] != total:
            if len(self._fragments) >= _MAX_FRAGMENT_SETS:
                self._fragments.popitem(last=False)
            entry = {"total": total, "parts": {}, "size": 0, "t": now}
            self._fragments[frag_id] = entry
        if num not in entry["parts"]:
            entry["size"] += len(data)
        entry["parts"][num] = data
        limit = self.max_message_size
        if limit and entry["size"] > limit:
            del self._fragments[frag_id]
            raise BridgeError("fragment: reassembled message exceeds max_message_size")
        if len(entry["parts"]) == total:
            del self._fragments[frag_id]
            text = "".join(entry["parts"][i] for i in range(total))
            self.received -= 1
            inner = self._decode(text)
            self._dispatch(inner, depth + 1)

    def _op_set_level(self, frame: Dict[str, Any]) -> None:
        level = frame.get("level")
        if level in LEVELS:
            self.level = LEVELS[level]

    def _op_auth(self, frame: Dict[str, Any]) -> None:
        if not self.policy.authenticate:
            self.status("info", "auth: this bridge does not require authentication", frame.get("id"))
            return
        if self.authenticated:
            return
        try:
            check_mac(self.policy.secret, frame, self.wall())
        except AuthError as exc:
            _log.warning("client %s (%s) failed to authenticate: %s", self.client_id, self.peer, exc)
            self.status("error", str(exc), frame.get("id"))
            if self.close_cb is not None:
                self.close_cb(1008, "authentication failed")
            return
        self.authenticated = True
        _log.info("client %s (%s) authenticated", self.client_id, self.peer)
        self.status("info", "authenticated", frame.get("id"))

    def _denied(self, what: str, name: str) -> NoReturn:
        raise BridgeError("%s %s: not allowed by this bridge's allow-list" % (what, name))

    def _op_advertise(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        type_name = _get(frame, "type", (str,), required=True)
        latch = bool(_get(frame, "latch", (bool, int), default=False))
        queue_size = int(min(_nonneg_int(frame, "queue_size") or 100, 1000))
        if not self.policy.may_publish(topic):
            self._denied("advertise", topic)
        self.backend.advertise(self, topic, type_name, latch, queue_size)
        self.advertised.add(topic)
        self.status("info", "advertised %s" % topic, frame.get("id"))

    def _op_unadvertise(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        if topic not in self.advertised:
            raise BridgeError("unadvertise: %s is not advertised by this client" % topic, "warning")
        self.advertised.discard(topic)
        self.backend.unadvertise(self, topic)

    def _op_publish(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        msg = _get(frame, "msg", (dict,), default={})
        if not self.policy.may_publish(topic):
            self._denied("publish", topic)
        implicit = topic not in self.advertised
        missing = self.backend.publish(self, topic, msg)
        if implicit:
            self.advertised.add(topic)
        if missing:
            self.status(
                "warning",
                "publish %s: fields filled with defaults: %s" % (topic, ", ".join(missing[:20])),
                frame.get("id"),
            )

    def _op_subscribe(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        type_name = _get(frame, "type", (str,))
        if type_name == "":
            type_name = None
        sub_id = frame.get("id")
        if sub_id is not None and (not isinstance(sub_id, (str, int)) or isinstance(sub_id, bool)):
            raise BridgeError("subscribe: 'id' must be a string or an integer")
        compression = _get(frame, "compression", (str,), default="none")
        if compression not in COMPRESSIONS:
            raise BridgeError("subscribe: unknown compression %r (none, png, cbor, cbor-raw)" % compression[:20])
        fragment_size = _get(frame, "fragment_size", (int,))
        if fragment_size is not None and fragment_size <= 0:
            raise BridgeError("subscribe: fragment_size must be > 0")
        opts = {
            "throttle_rate": _nonneg_int(frame, "throttle_rate"),
            "queue_length": int(min(_nonneg_int(frame, "queue_length"), 10000)),
            "fragment_size": fragment_size,
            "compression": compression,
        }
        if not self.policy.may_subscribe(topic):
            self._denied("subscribe", topic)
        sub = self.subs.get(topic)
        if sub is None:
            resolved = self.backend.subscribe(self, topic, type_name)
            sub = _TopicSub(topic, resolved)
            self.subs[topic] = sub
        elif type_name and sub.type and _same_type(type_name, sub.type) is False:
            raise BridgeError("subscribe: %s has type %s, not %s" % (topic, sub.type, type_name))
        key = sub_id if sub_id is not None else "subscribe:%s:%d" % (topic, next(self._ids))
        sub.by_id.pop(key, None)
        sub.by_id[key] = opts
        sub.merge()
        self.status("info", "subscribed to %s" % topic, sub_id)

    def _op_unsubscribe(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        sub = self.subs.get(topic)
        if sub is None:
            raise BridgeError("unsubscribe: not subscribed to %s" % topic, "warning")
        sub_id = frame.get("id")
        if sub_id is not None and sub_id in sub.by_id:
            del sub.by_id[sub_id]
        elif sub_id is not None and len(sub.by_id) > 1:
            raise BridgeError("unsubscribe: no subscription %r on %s" % (sub_id, topic), "warning")
        else:
            sub.by_id.clear()
        if sub.by_id:
            sub.merge()
            return
        self._drop_sub(sub)

    def _drop_sub(self, sub: Any) -> None:
        del self.subs[sub.topic]
        if sub.timer is not None:
            sub.timer.cancel()
            sub.timer = None
        self.backend.unsubscribe(self, sub.topic)

    def _op_call_service(self, frame: Dict[str, Any]) -> None:
        service = _name(frame, "service")
        args = frame.get("args")
        if args is not None and not isinstance(args, (list, dict)):
            raise BridgeError("call_service: 'args' must be a list or an object")
        timeout = _get(frame, "timeout", (int, float))
        if timeout is not None and not timeout > 0:
            timeout = None
        fragment_size = _get(frame, "fragment_size", (int,))
        compression = _get(frame, "compression", (str,), default="none")
        if compression not in ("none", "png"):
            compression = "none"
        call_id = frame.get("id")
        if not self.policy.may_call(service):
            _log.warning("client %s (%s): call_service %s denied by the allow-list", self.client_id, self.peer, service)
            self.status("error", "call_service %s: not allowed by this bridge's allow-list" % service, call_id)
            self._service_done(
                service,
                call_id,
                fragment_size,
                compression,
                False,
                "service %s is not allowed by this bridge's allow-list" % service,
            )
            return

        def done(ok: bool, values: Any) -> None:
            self._service_done(service, call_id, fragment_size, compression, ok, values)

        try:
            self.backend.call_service(self, service, args, timeout, done)
        except BridgeError as exc:
            self.status("error", str(exc), call_id)
            done(False, str(exc))

    def _service_done(
        self, service: str, call_id: Any, fragment_size: Optional[int], compression: str, ok: bool, values: Any
    ) -> None:
        if self.closed:
            return
        frame = {"op": "service_response", "service": service, "values": values, "result": bool(ok)}
        if call_id is not None:
            frame["id"] = call_id
        self.send(frame, fragment_size, compression)

    def _op_advertise_service(self, frame: Dict[str, Any]) -> None:
        service = _name(frame, "service")
        type_name = _get(frame, "type", (str,), required=True)
        if not self.policy.may_call(service) or service.startswith("/rosapi/"):
            self._denied("advertise_service", service)
        self.backend.advertise_service(self, service, type_name)
        self.services.add(service)
        self.status("info", "advertised service %s" % service, frame.get("id"))

    def _op_unadvertise_service(self, frame: Dict[str, Any]) -> None:
        service = _name(frame, "service")
        if service not in self.services:
            raise BridgeError("unadvertise_service: %s is not advertised by this client" % service, "warning")
        self.services.discard(service)
        self.backend.unadvertise_service(self, service)

    def _op_service_response(self, frame: Dict[str, Any]) -> None:
        service = _name(frame, "service")
        call_id = frame.get("id")
        if call_id is None:
            raise BridgeError("service_response: missing 'id'")
        values = frame.get("values")
        result = frame.get("result", True)
        # result: false still hands the values to the ROS caller when they are an object (as
        # rosbridge, which ignores the flag); the backend logs it
        self.backend.service_response(self, service, call_id, values, result is not False)

    # ----------------------------------------------------------------- teardown

    def close(self) -> None:
        """Release everything this client held in ROS (idempotent)."""
        if self.closed:
            return
        self.closed = True
        for sub in list(self.subs.values()):
            if sub.timer is not None:
                sub.timer.cancel()
        self.subs.clear()
        self._fragments.clear()
        try:
            self.backend.session_closed(self)
        except Exception:
            _log.exception("client %s: error while releasing ROS resources", self.client_id)


def _same_type(a: Any, b: Any) -> Any:
    try:
        return normalize_type(a) == normalize_type(b)
    except ConversionError:
        return False

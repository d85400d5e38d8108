"""rosbridge v2 protocol session: parse, check, dispatch, merge subscriptions, queue output.

ROS- and transport-free, on the event loop thread: ``receive()`` takes client frames; a *backend*
(:class:`rbd_bridge.ros.backend.RosBackend`, or a fake) does the ROS work (a method per op, ``session_closed``,
``begin_batch`` / ``end_batch`` around one read's frames); frames for the client go to a bounded ``OutQueue``.
"""

import collections
import itertools
import json
import logging
import time
from typing import Any, Callable, Dict, Optional

from rbd_bridge.core import encoding
from rbd_bridge.core.security import AuthError, check_mac
from rbd_bridge.core.types import BridgeError, ConversionError, normalize_type

__all__ = ["Session", "LEVELS", "COMPRESSIONS"]

LEVELS = {"none": 0, "error": 1, "warning": 2, "info": 3}
COMPRESSIONS = ("none", "png", "cbor", "cbor-raw")

_log = logging.getLogger("rbd_bridge")


class _TopicSub:
    """A client's merged subscriptions to one topic (:meth:`merge` sets the options)."""

    def __init__(self, topic: str, type_name: str) -> None:
        self.topic = topic
        self.type = type_name
        self.by_id = collections.OrderedDict()  # id -> (throttle_rate, queue_length, fragment_size, compression)
        self.last = -1e18
        self.pending = ()
        self.timer = None

    def merge(self) -> None:
        throttles, lengths, sizes, compressions = zip(*self.by_id.values())
        self.throttle = min(throttles) / 1000.0
        self.queue_length = max(lengths)
        self.fragment_size = min(filter(None, sizes), default=None)
        self.compression = compressions[-1]
        self.pending = collections.deque(self.pending, maxlen=self.queue_length)  # the newest kept


def _get(frame: Dict[str, Any], key: str, kinds: Any, default: Any = None, required: bool = False) -> Any:
    value = frame.get(key, default)
    if value is None:
        if required:
            raise BridgeError("%s: missing field %r" % (frame.get("op"), key))
        return default
    if (isinstance(value, bool) and bool not in kinds) or not isinstance(value, kinds):
        raise BridgeError("%s: field %r has the wrong type" % (frame.get("op"), key))
    return value


def _name(frame: Dict[str, Any], key: str) -> str:
    value = frame.get(key)
    if value.__class__ is not str:
        value = _get(frame, key, (str,), required=True)
    if len(value) > 1024 or value.split() != [value]:  # empty, or with whitespace
        raise BridgeError("%s: invalid %s name %r" % (frame.get("op"), key, value[:80]))
    return value if value[0] == "/" else "/" + value


def _nonneg(frame: Dict[str, Any], key: str) -> Any:
    value = _get(frame, key, (int, float), default=0)
    if value != value or value < 0:
        raise BridgeError("%s: %r must be >= 0" % (frame.get("op"), key))
    return value


class Session:
    """One WebSocket client speaking rosbridge v2.

    Args:
        client_id: Unique id of this connection (int).
        backend: The backend (module doc).
        policy: :class:`rbd_bridge.core.security.Policy`.
        out: :class:`rbd_bridge.core.outqueue.OutQueue` for frames to the client.
        call_later: ``call_later(delay_s, fn)`` returning a handle with ``cancel()``.
        close: Callable(code, reason) closing the connection.
        peer: Client address text (logs only).
        clock: Monotonic clock (throttling, fragment expiry).
        wall: Wall clock in seconds (auth time window).
        wire: The transport's framing of a payload (str or bytes) as queued; identity by default.
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
        wire: Callable[[Any], Any] = lambda payload: payload,
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
        self.wire = wire
        self.level = 0
        self.authenticated = not policy.authenticate
        self.closed = False
        self.subs = {}
        self.advertised = set()
        self.services = set()
        self._fragments = encoding.Reassembler()
        self._ids = itertools.count(1)
        self.errors = 0
        self.max_message_size = None
        self.direct = None  # a transport's direct(message, compression) -> True if it sent the frame (any thread)
        self._rejected = 0
        self._rejected_logged = -1e18

    def receive(self, data: Any) -> None:
        """Handle one frame from the client (str or bytes). Never raises."""
        if self.closed:
            return
        try:
            frame = self._decode(data)
        except BridgeError as exc:
            self._rejected_frame(exc, {})
            return
        self._dispatch(frame, 0)

    def _dispatch(self, frame: Dict[str, Any], depth: int) -> None:
        try:
            op = frame.get("op")
            if not isinstance(op, str):
                raise BridgeError("frame without a string 'op' field")
            handler = getattr(self, "_op_" + op, None)
            if handler is None:
                raise BridgeError("unsupported op %r" % op[:40])
            if not self.authenticated and op != "auth":
                # as rosbridge: anything but auth on an unauthenticated connection ends it
                _log.warning("client %s (%s) sent %r before authenticating: closing", self.client_id, self.peer, op)
                self._end(1008, "authentication required")
            elif op == "fragment":
                self._op_fragment(frame, depth)
            else:
                handler(frame)
        except (BridgeError, ConversionError) as exc:
            self._rejected_frame(exc, frame)
        except Exception as exc:  # a bug must not end the session
            self.errors += 1
            _log.exception("client %s: internal error", self.client_id)
            self.status("error", "internal error: %s" % exc)

    def _rejected_frame(self, exc: Exception, frame: Dict[str, Any]) -> None:
        self.errors += 1
        now = self.clock()
        self._rejected += 1
        if now - self._rejected_logged >= 1.0:  # at most a line per second per client
            _log.warning("client %s (%s): frame rejected (%d): %s", self.client_id, self.peer, self._rejected, exc)
            self._rejected, self._rejected_logged = 0, now
        text = str(exc) if isinstance(exc, BridgeError) else "%s: %s" % (frame.get("op"), exc)
        self.status(getattr(exc, "level", "error"), text, frame.get("id"))  # with the frame's id, as rosbridge's

    @staticmethod
    def _decode(data: Any) -> Dict[str, Any]:
        if isinstance(data, (bytes, bytearray, memoryview)):
            try:
                frame = encoding.cbor_loads(data)
            except encoding.DecodeError:
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

    def status(self, level: str, text: str, frame_id: Any = None) -> None:
        """Send a status frame if the client asked for this level (set_level)."""
        if self.level == 0 or LEVELS.get(level, 3) > self.level:
            return
        frame = {"op": "status", "level": level, "msg": text}
        if frame_id is not None:
            frame["id"] = frame_id
        self._push(encoding.json_dumps(frame))

    def _push(self, payload: Any, topic: str = None, limit: int = 0) -> None:
        self.out.push(self.wire(payload), topic, limit)

    def _push_text(self, text: str, fragment_size: Optional[int], compression: str, topic: Any, limit: int) -> None:
        op = "png" if compression == "png" else "fragment"
        if op == "png":
            text = encoding.png_encode(text)
        if fragment_size and len(text) > fragment_size:
            for part in encoding.fragment(text, fragment_size, "%s:%d" % (op, next(self._ids)), op):
                self._push(part, topic, 0)
        else:
            self._push(encoding.json_dumps({"op": "png", "data": text}) if op == "png" else text, topic, limit)

    def deliver(self, topic: str, message: Any) -> None:
        """Take one :class:`rbd_bridge.core.fanout.TopicMessage` of a subscribed topic (throttle/queue)."""
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
        sub.pending.append(message)  # (it keeps queue_length messages, the newest)
        if sub.timer is None and sub.pending:
            sub.timer = self.call_later(max(0.0, sub.last + sub.throttle - now), lambda: self._flush(topic))

    def direct_compression(self, topic: str) -> Optional[str]:
        """Compression of topic if a message may bypass :meth:`deliver` (:attr:`direct`), else None.

        Only without throttle, fragmentation or PNG, where the frame is the message's own. Any thread.
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
        if sub.pending:
            sub.last = self.clock()
            self._emit(sub, sub.pending.popleft(), 0)
            if sub.pending:
                sub.timer = self.call_later(sub.throttle, lambda: self._flush(topic))

    def _emit(self, sub: Any, message: Any, limit: int) -> None:
        compression = sub.compression
        if compression == "png" or (sub.fragment_size and compression == "none"):
            self._push_text(message.frame("none"), sub.fragment_size, compression, sub.topic, limit)
        else:
            self.out.push(message.wire(compression, self.wire), sub.topic, limit)

    def send_service_request(self, service: str, call_id: Any, args: Any) -> None:
        """Forward a ROS call of a client-hosted service to the client."""
        self._push(encoding.json_dumps({"op": "call_service", "id": call_id, "service": service, "args": args}))

    def _op_fragment(self, frame: Dict[str, Any], depth: int) -> None:
        if depth > 1:
            raise BridgeError("fragment: fragments nested too deeply")
        try:
            text = self._fragments.add(frame, self.clock(), self.max_message_size)
        except encoding.DecodeError as exc:
            raise BridgeError("fragment: %s" % exc) from None
        if text is not None:
            self._dispatch(self._decode(text), depth + 1)

    def _op_set_level(self, frame: Dict[str, Any]) -> None:
        level = frame.get("level")
        if isinstance(level, str) and level in LEVELS:
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
            self._end(1008, "authentication failed")
            return
        self.authenticated = True
        _log.info("client %s (%s) authenticated", self.client_id, self.peer)
        self.status("info", "authenticated", frame.get("id"))

    @staticmethod
    def _allow(allowed: bool, what: str, name: str) -> None:
        if not allowed:
            raise BridgeError("%s %s: not allowed by this bridge's allow-list" % (what, name))

    def _op_advertise(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        type_name = _get(frame, "type", (str,), required=True)
        latch = bool(_get(frame, "latch", (bool, int), default=False))
        queue_size = int(min(_nonneg(frame, "queue_size") or 100, 1000))
        self._allow(self.policy.may_publish(topic), "advertise", topic)
        self.backend.advertise(self, topic, type_name, latch, queue_size)
        self.advertised.add(topic)
        self.status("info", "advertised %s" % topic, frame.get("id"))

    def _withdraw(self, frame: Dict[str, Any], key: str, held: set, release: Callable[..., Any]) -> None:
        name = _name(frame, key)
        if name not in held:
            raise BridgeError("%s: %s is not advertised by this client" % (frame["op"], name), "warning")
        held.discard(name)
        release(self, name)

    def _op_unadvertise(self, frame: Dict[str, Any]) -> None:
        self._withdraw(frame, "topic", self.advertised, self.backend.unadvertise)

    def _op_publish(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        msg = _get(frame, "msg", (dict,), default={})
        self._allow(self.policy.may_publish(topic), "publish", topic)
        missing = self.backend.publish(self, topic, msg)
        self.advertised.add(topic)  # publish without advertise advertises implicitly
        if missing:
            text = "publish %s: fields filled with defaults: %s" % (topic, ", ".join(missing[:20]))
            self.status("warning", text, frame.get("id"))

    def _op_subscribe(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        type_name = _get(frame, "type", (str,)) or None
        sub_id = _get(frame, "id", (str, int))
        compression = _get(frame, "compression", (str,), default="none")
        if compression not in COMPRESSIONS:
            raise BridgeError("subscribe: unknown compression %r (none, png, cbor, cbor-raw)" % compression[:20])
        fragment_size = _get(frame, "fragment_size", (int,))
        if fragment_size is not None and fragment_size <= 0:
            raise BridgeError("subscribe: fragment_size must be > 0")
        throttle_rate = _nonneg(frame, "throttle_rate")
        opts = (throttle_rate, int(min(_nonneg(frame, "queue_length"), 10000)), fragment_size, compression)
        self._allow(self.policy.may_subscribe(topic), "subscribe", topic)
        sub = self.subs.get(topic)
        if sub is None:
            sub = _TopicSub(topic, self.backend.subscribe(self, topic, type_name))
        elif type_name and sub.type and normalize_type(type_name) != normalize_type(sub.type):
            raise BridgeError("subscribe: %s has type %s, not %s" % (topic, sub.type, type_name))
        key = sub_id if sub_id is not None else "subscribe:%s:%d" % (topic, next(self._ids))
        sub.by_id.pop(key, None)
        sub.by_id[key] = opts
        sub.merge()
        self.subs[topic] = sub  # (a new one only once merged: direct_compression reads it from any thread)
        self.status("info", "subscribed to %s" % topic, sub_id)

    def _op_unsubscribe(self, frame: Dict[str, Any]) -> None:
        topic = _name(frame, "topic")
        sub = self.subs.get(topic)
        if sub is None:
            raise BridgeError("unsubscribe: not subscribed to %s" % topic, "warning")
        sub_id = frame.get("id")
        if sub.by_id.pop(sub_id, None) is None:  # no id (None is never a key), or not one of ours
            if sub_id is not None and len(sub.by_id) > 1:
                raise BridgeError("unsubscribe: no subscription %r on %s" % (sub_id, topic), "warning")
            sub.by_id.clear()
        if sub.by_id:
            sub.merge()
            return
        del self.subs[topic]
        if sub.timer is not None:
            sub.timer.cancel()
        self.backend.unsubscribe(self, topic)

    def _op_call_service(self, frame: Dict[str, Any]) -> None:
        service = _name(frame, "service")
        args = _get(frame, "args", (list, dict))
        timeout = _get(frame, "timeout", (int, float))
        fragment_size = _get(frame, "fragment_size", (int,))
        compression = "png" if frame.get("compression") == "png" else "none"
        call_id = frame.get("id")

        def done(ok: bool, values: Any) -> None:
            if not self.closed:
                reply = {"op": "service_response", "service": service, "values": values, "result": bool(ok)}
                if call_id is not None:
                    reply["id"] = call_id
                self._push_text(encoding.json_dumps(reply), fragment_size, compression, None, 0)

        try:
            if not self.policy.may_call(service):
                _log.warning("client %s (%s): call_service %s denied", self.client_id, self.peer, service)
                self._allow(False, "call_service", service)
            self.backend.call_service(self, service, args, timeout if timeout and timeout > 0 else None, done)
        except BridgeError as exc:
            self.status("error", str(exc), call_id)
            done(False, str(exc))  # a blocking client never hangs

    def _op_advertise_service(self, frame: Dict[str, Any]) -> None:
        service = _name(frame, "service")
        type_name = _get(frame, "type", (str,), required=True)
        self._allow(self.policy.may_call(service) and not service.startswith("/rosapi/"), "advertise_service", service)
        self.backend.advertise_service(self, service, type_name)
        self.services.add(service)
        self.status("info", "advertised service %s" % service, frame.get("id"))

    def _op_unadvertise_service(self, frame: Dict[str, Any]) -> None:
        self._withdraw(frame, "service", self.services, self.backend.unadvertise_service)

    def _op_service_response(self, frame: Dict[str, Any]) -> None:
        service = _name(frame, "service")
        if frame.get("id") is None:
            raise BridgeError("service_response: missing 'id'")
        # result false still hands object values to the ROS caller (rosbridge ignores the
        # flag; roslibpy handlers returning False rely on it); the backend logs it
        ok = frame.get("result", True) is not False
        self.backend.service_response(self, service, frame["id"], frame.get("values"), ok)

    def _end(self, code: int, reason: str) -> None:
        if self.close_cb is not None:
            self.close_cb(code, reason)
        self.close()

    def close(self) -> None:
        """Release everything this client held in ROS (idempotent)."""
        if self.closed:
            return
        self.closed = True
        for sub in self.subs.values():
            if sub.timer is not None:
                sub.timer.cancel()
        self.subs.clear()
        self._fragments = encoding.Reassembler()
        try:
            self.backend.session_closed(self)
        except Exception:
            _log.exception("client %s: error while releasing ROS resources", self.client_id)

"""WebSocket transport on asyncio and wsproto, one :class:`rbd_bridge.core.session.Session` per client.

wsproto does the handshake and the frames :meth:`_Connection._fast` does not take (README,
Design: why); no extension is negotiated.
"""

import asyncio
import contextlib
import itertools
import logging
import struct
import threading
from typing import Any, Callable, List, Optional

from wsproto import ConnectionType, WSConnection
from wsproto.events import AcceptConnection, RejectConnection, RejectData, Request
from wsproto.frame_protocol import FrameProtocol, Opcode, ParseFailed, XorMaskerSimple
from wsproto.utilities import RemoteProtocolError

from rbd_bridge.core.outqueue import OutQueue
from rbd_bridge.core.session import Session

__all__ = ["BridgeServer", "wire"]

_log = logging.getLogger("rbd_bridge")
_RECV_SIZE = 65536  # asyncio reads this much per call (its 256 KiB default costs an mmap per read)
_JOIN_BYTES = 65536  # queued small frames leave joined in writes of up to this size
_MAX_HANDSHAKE = 16384
_FAST_OPCODES = (1, 2, 9, 10)  # text, binary, ping, pong
try:  # websockets' C helper when installed (the venv); else wsproto's masker
    from websockets.speedups import apply_mask as _apply_mask
except ImportError:
    _apply_mask = None


def wire(payload: Any) -> bytes:
    """One unmasked, final server frame: text for str, binary for bytes (RFC 6455 5.2)."""
    if isinstance(payload, str):
        payload, first = payload.encode("utf-8"), 0x81
    else:
        first = 0x82
    n = len(payload)
    if n < 126:
        return bytes((first, n)) + payload
    if n < 65536:
        return struct.pack("!BBH", first, 126, n) + payload
    return struct.pack("!BBQ", first, 127, n) + payload


class _Connection(asyncio.Protocol):
    """One client connection: handshake, messages in, writes with flow control."""

    def __init__(self, server: "BridgeServer") -> None:
        self.server = server
        self.ws = WSConnection(ConnectionType.SERVER)  # the handshake
        self.proto = None  # then wsproto's frame protocol
        self.session = None
        self.out = None
        self.closing = False
        self.paused = False
        self.parts = []
        self.parts_size = 0
        self.buf = bytearray()  # an incomplete frame of the fast path
        self.fast = True  # False once wsproto has the stream
        self.alive = True
        self.head_buf = bytearray()
        # Writes may also come from a ROS thread (try_direct); the lock orders them with
        # the loop's writes, and head is the unsent rest of a direct write (goes first).
        self.lock = threading.RLock()
        self.head = None

    def connection_made(self, transport: Any) -> None:
        self.transport = transport
        peer = transport.get_extra_info("peername")
        self.peer = "%s:%s" % tuple(peer[:2]) if peer else "?"
        transport.set_write_buffer_limits(high=1 << 18)
        transport.max_size = _RECV_SIZE
        self.sock = getattr(transport, "_sock", None)  # the transport's own non-blocking socket
        self.timer = self.server.loop.call_later(10.0, transport.abort)  # no handshake within 10 s

    def data_received(self, data: bytes) -> None:
        if self.proto is None:
            self._handshake(data)
            return
        backend = self.server.backend
        backend.begin_batch()  # the publishes of this read leave together, per ROS peer
        try:
            if self.fast:
                data = self._fast(data)
                if not data or self.closing:
                    return
                self.fast = False
            self.proto.receive_bytes(data)
            for frame in self.proto.received_frames():
                self.alive = True
                opcode = frame.opcode
                if opcode in (Opcode.TEXT, Opcode.BINARY):
                    self._message(frame.payload, frame.message_finished)
                elif opcode is Opcode.PING:
                    self._write(self.proto.pong(frame.payload))
                elif opcode is Opcode.CLOSE:
                    self.close(frame.payload[0])  # answered with the client's code
                if self.closing:
                    return
        except ParseFailed as exc:  # RFC 6455 violations, invalid UTF-8 (1007) among them
            self.close(exc.code, str(exc))
        except UnicodeDecodeError:  # a text frame of the fast path
            self.close(1007, "invalid UTF-8 in a text message")
        except Exception:  # never leave a half-dead connection behind a bug
            _log.exception("client %s: frame handling error", self.peer)
            self.close(1011, "internal error")
        finally:
            backend.end_batch()

    def _fast(self, data: bytes) -> bytes:
        """Handle the complete common frames of buf + data; return the bytes wsproto must take."""
        buf = self.buf
        buf += data
        limit = self.server.max_message_size
        pos, end = 0, len(buf)
        while not self.closing and end - pos >= 2:
            b0, b1 = buf[pos], buf[pos + 1]
            length, head = b1 & 0x7F, pos + 2
            if length == 126:
                if end - pos < 4:
                    break
                length, head = struct.unpack_from("!H", buf, head)[0], pos + 4
            elif length == 127:
                if end - pos < 10:
                    break
                length, head = struct.unpack_from("!Q", buf, head)[0], pos + 10
            opcode = b0 & 0x0F
            if b0 & 0xF0 != 0x80 or not b1 & 0x80 or opcode not in _FAST_OPCODES or (opcode > 8 and length > 125):
                rest = bytes(buf[pos:])  # anything else: wsproto from this frame on
                del buf[:]
                return rest
            if limit and length > limit:
                self.close(1009, "message larger than max_message_size")
                return b""
            if end < head + 4 + length:
                break
            payload, mask = bytes(buf[head + 4 : head + 4 + length]), bytes(buf[head : head + 4])
            payload = _apply_mask(payload, mask) if _apply_mask else XorMaskerSimple(mask).process(payload)
            pos = head + 4 + length
            self.alive = True
            if opcode == 9:
                self._write(self.proto.pong(payload))
            elif opcode == 1:
                self.session.receive(payload.decode("utf-8"))  # (invalid UTF-8: 1007 in data_received)
            elif opcode == 2:
                self.session.receive(payload)
        del buf[:pos]
        return b""

    def _message(self, data: Any, finished: bool) -> None:
        """A frame of a message from wsproto (str or bytes): join the parts; over the limit in bytes: 1009."""
        self.parts.append(data)
        self.parts_size += len(data.encode() if isinstance(data, str) else data)
        limit = self.server.max_message_size
        if limit and self.parts_size > limit:
            self.close(1009, "message larger than max_message_size")
        elif finished:
            data, self.parts, self.parts_size = data[:0].join(self.parts), [], 0
            self.session.receive(data)

    def pause_writing(self) -> None:
        self.paused = True

    def resume_writing(self) -> None:
        self.paused = False
        self.flush()

    def connection_lost(self, exc: Optional[Exception]) -> None:
        with self.lock:  # no direct write is in progress once this returns
            self.closing = True
        self.timer.cancel()
        if self.session is not None:
            self.server.closed(self)

    def _handshake(self, data: bytes) -> None:
        # wsproto gets the request alone: frames a client sends without waiting for the
        # answer go to the connection once it is open (a wsproto server drops them)
        self.head_buf += data
        end = self.head_buf.find(b"\r\n\r\n")
        if end < 0:
            if len(self.head_buf) > _MAX_HANDSHAKE:
                self._reject(RejectConnection(status_code=431), "request too large")
            return
        head, rest = bytes(self.head_buf[: end + 4]), bytes(self.head_buf[end + 4 :])
        try:
            self.ws.receive_data(head)
            request = next((e for e in self.ws.events() if isinstance(e, Request)), None)
        except RemoteProtocolError as exc:
            self._reject(exc.event_hint, str(exc))
            return
        if request is None:
            self._reject(RejectConnection(status_code=400), "not a WebSocket upgrade request")
            return
        self.timer.cancel()
        self.transport.write(self.ws.send(AcceptConnection()))
        self.proto = FrameProtocol(client=False, extensions=[])
        self.server.opened(self)
        self._keepalive(False)
        if rest:
            self.data_received(rest)

    def _reject(self, event: Any, text: str) -> None:
        status = getattr(event, "status_code", 400)
        status = 426 if status == 400 and "Upgrade" in text else status  # plain HTTP to a WebSocket server
        body = (text + "\n").encode()
        headers = [(b"content-type", b"text/plain"), (b"content-length", b"%d" % len(body))]
        with contextlib.suppress(Exception):  # the handshake state machine refuses: just drop the connection
            reject = RejectConnection(status_code=status, headers=headers, has_body=True)
            self.transport.write(self.ws.send(reject) + self.ws.send(RejectData(data=body)))
        self.transport.close()

    def _write(self, data: bytes) -> None:
        """Loop thread: write data after any unsent rest of a direct write."""
        with self.lock:
            if self.head is not None:
                head, self.head = self.head, None
                self.transport.write(head)
            self.transport.write(data)

    def flush(self) -> None:
        """Write queued frames (small ones joined, big ones alone) until the transport asks to pause."""
        with self.lock:  # (the unsent rest of a direct write goes first, in _write)
            parts, size = [], 0
            while not self.paused and not self.closing:
                frame = self.out.pop()
                if frame is None:
                    break
                if parts and (len(frame) >= 16384 or size >= _JOIN_BYTES):
                    self._write(b"".join(parts))
                    parts, size = [], 0
                parts.append(frame)
                size += len(frame)
            if not self.closing:
                self._write(b"".join(parts))  # (one frame: written as it is, no copy; none: only the rest)

    def try_direct(self, message: Any, compression: str) -> bool:
        """Any thread: send a topic frame at once if nothing is queued and the socket takes it; True if taken.

        Otherwise (False, never waiting) the caller queues it as usual: order, the bounded
        queue and the stalled-client guarantee are unchanged.
        """
        if self.paused or self.closing:  # (session.direct only after the handshake, with a socket: opened)
            return False
        frame = message.wired.get(compression) or message.wire(compression, wire)  # (no call per client)
        with self.lock:
            if self.closing or self.paused or self.head or len(self.out) or self.transport.get_write_buffer_size():
                return False
            try:
                sent = self.sock.send(frame)
            except OSError:  # full (BlockingIOError) or broken: the loop sees it next time
                return False
            if sent == len(frame):
                return True
            self.head = frame[sent:]
        with contextlib.suppress(RuntimeError):  # loop closed
            self.server.loop.call_soon_threadsafe(self.flush)
        return True

    def close(self, code: int = 1000, reason: str = "") -> None:
        """Send a close frame (or answer the client's) and drop the connection shortly after."""
        if self.closing:
            return
        self._write(self.proto.close(code, reason[:120] or None))  # (only open connections are closed)
        with self.lock:
            self.closing = True
        self.server.loop.call_later(2.0, self.transport.abort)
        self.transport.close()

    def _keepalive(self, ping: bool) -> None:
        """Ping every ping_interval; a client silent for ping_timeout after a ping is dropped."""
        server = self.server
        if self.closing or not server.ping_interval:
            return
        if ping:
            self.alive = False
            self._write(self.proto.ping())
            self.timer = server.loop.call_later(server.ping_timeout or server.ping_interval, self._keepalive, False)
        elif self.alive:
            self.timer = server.loop.call_later(server.ping_interval, self._keepalive, True)
        else:
            _log.warning("client %s: no answer to ping, closing", self.peer)
            self.close(1011, "keepalive ping timeout")
            self.transport.abort()


class BridgeServer:
    """Serve rosbridge v2 over WebSocket.

    Args:
        loop: The asyncio event loop.
        backend: The ROS side (see :mod:`rbd_bridge.core.session`).
        policy: :class:`rbd_bridge.core.security.Policy`.
        host: Bind address.
        port: TCP port (0 = any free port; :attr:`port` after :meth:`start`).
        max_message_size: Largest incoming message [bytes] (bigger closes with 1009).
        max_queue_frames: Outgoing frames kept per client (the oldest are dropped beyond).
        max_queue_bytes: Outgoing bytes kept per client (the oldest are dropped beyond).
        ping_interval: Ping period [s] (None = off); silent ping_timeout s after a ping: dropped.
        ping_timeout: See ping_interval.
        on_clients: Callable(count) called when the number of clients changes.
        direct_writes: Other threads may send topic frames at once to idle clients (try_direct).
    """

    def __init__(
        self,
        loop: Any,
        backend: Any,
        policy: Any,
        host: str = "127.0.0.1",
        port: int = 9090,
        max_message_size: int = 10000000,
        max_queue_frames: int = 1000,
        max_queue_bytes: int = 16 * 1024 * 1024,
        ping_interval: Optional[float] = 20.0,
        ping_timeout: Optional[float] = 20.0,
        on_clients: Optional[Callable[[int], None]] = None,
        direct_writes: bool = True,
    ) -> None:
        self.loop, self.backend, self.policy, self.host, self.port = loop, backend, policy, host, port
        self.max_message_size = max_message_size
        self.max_queue_frames, self.max_queue_bytes = max_queue_frames, max_queue_bytes
        self.ping_interval, self.ping_timeout = ping_interval, ping_timeout
        self.on_clients = on_clients or (lambda count: None)
        self.direct_writes = direct_writes
        self.sessions = {}
        self._connections = {}
        self._ids = itertools.count(1)
        self._server = None

    async def start(self) -> int:
        """Bind and listen; return the port."""
        self._server = await self.loop.create_server(lambda: _Connection(self), self.host, self.port, backlog=128)
        self.port = self._server.sockets[0].getsockname()[1]
        return self.port

    async def stop(self) -> None:
        """Close every connection and the listening socket."""
        if self._server is not None:
            self._server.close()
            for conn in list(self._connections.values()):
                conn.close(1001, "bridge shutting down")
            await self._server.wait_closed()
            self._server = None

    def opened(self, conn: _Connection) -> None:
        """A handshake completed: give the connection its session."""
        client_id = next(self._ids)
        conn.out = OutQueue(self.max_queue_frames, self.max_queue_bytes, notify=conn.flush)
        conn.session = Session(
            client_id,
            self.backend,
            self.policy,
            conn.out,
            self.loop.call_later,
            close=conn.close,
            peer=conn.peer,
            wire=wire,
        )
        conn.session.max_message_size = self.max_message_size
        if conn.sock is not None and self.direct_writes:
            conn.session.direct = conn.try_direct
        self.sessions[client_id] = conn.session
        self._connections[client_id] = conn
        self._clients_changed()
        _log.info("client %d connected from %s (%d connected)", client_id, conn.peer, len(self.sessions))

    def closed(self, conn: _Connection) -> None:
        """A connection ended: release its session's ROS resources."""
        session = conn.session
        session.close()
        self.sessions.pop(session.client_id, None)
        self._connections.pop(session.client_id, None)
        self._clients_changed()
        if conn.out.dropped:
            _log.warning("client %d: %d outgoing frames dropped (slow client)", session.client_id, conn.out.dropped)
        _log.info("client %d disconnected (%d connected)", session.client_id, len(self.sessions))

    def client_peers(self) -> List[str]:
        """``host:port`` of every connected client (for the node's ``~stats``, read by preflight)."""
        return sorted(conn.peer for conn in list(self._connections.values()))

    def _clients_changed(self) -> None:
        try:
            self.on_clients(len(self.sessions))
        except Exception:
            _log.exception("client count callback failed")

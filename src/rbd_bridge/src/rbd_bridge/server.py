"""WebSocket transport (RFC 6455) on asyncio, one :class:`rbd_bridge.protocol.Session` per connection.

Why not a WebSocket library for the server: a frame here is parsed and answered in one
``data_received`` call, and outgoing frames are written straight to the socket, with no
coroutine hop per frame. That halves the bridge's per-message cost compared with the
``websockets`` library (measured), and gives exact flow control: while the kernel
socket buffer and asyncio's write buffer are full (``pause_writing``) frames wait in the
client's bounded :class:`rbd_bridge.protocol.OutQueue`, so a stalled client costs bounded
memory. It runs on Python 3.6+. The ``websockets`` library's C masking helper is used when
installed. No extensions (permessage-deflate) are negotiated; clients fall back to plain
frames, as the WebSocket spec requires.
"""

import asyncio
import base64
import hashlib
import itertools
import logging
import socket
import struct
import threading
from typing import Any, Callable, List, Optional

from rbd_bridge.protocol import OutQueue, Session

try:
    from websockets.speedups import apply_mask as _c_mask
except ImportError:  # pure Python fallback
    _c_mask = None

__all__ = ["BridgeServer", "unmask"]

_log = logging.getLogger("rbd_bridge")
_GUID = b"258EAFA5-E914-47DA-95CA-C5AB0DC85B11"
_MAX_HANDSHAKE = 16384
_RECV_SIZE = 65536
_JOIN_BYTES = 65536  # small outgoing frames are joined into writes of up to this size


def unmask(payload: bytes, mask: bytes) -> bytes:
    """XOR payload with the 4-byte client mask."""
    if not payload:
        return b""
    if _c_mask is not None:
        return _c_mask(payload, mask)
    n = len(payload)
    key = (mask * (n // 4 + 1))[:n]
    return (int.from_bytes(payload, "little") ^ int.from_bytes(key, "little")).to_bytes(n, "little")


def frame_header(opcode: int, length: int) -> bytes:
    """Header of an unmasked, final server frame."""
    if length < 126:
        return struct.pack("!BB", 0x80 | opcode, length)
    if length < 65536:
        return struct.pack("!BBH", 0x80 | opcode, 126, length)
    return struct.pack("!BBQ", 0x80 | opcode, 127, length)


def wire_frame(frame: Any) -> bytes:
    """A whole server frame (header + payload) for a text (str) or binary (bytes) message."""
    if isinstance(frame, str):
        data = frame.encode("utf-8")
        return frame_header(1, len(data)) + data
    return frame_header(2, len(frame)) + frame


def _close_payload(code: int, reason: str) -> bytes:
    return struct.pack("!H", code) + reason.encode("utf-8")[:120]


class _Connection(asyncio.Protocol):
    """One client connection: handshake, frame parsing, writes with flow control."""

    def __init__(self, server: "BridgeServer") -> None:
        self.server = server
        self.transport = None
        self.session = None
        self.out = None
        self.open = False
        self.closing = False
        self.paused = False
        self.buf = bytearray()
        self.parts = []
        self.parts_size = 0
        self.parts_opcode = 0
        self.alive = True
        self.timer = None
        self.peer = "?"
        # Writes may also come from a ROS thread (try_direct); the lock orders them with
        # the loop's writes, and head is the unsent rest of a direct write (goes first).
        self.lock = threading.RLock()
        self.head = None
        self.sock = None

    # ------------------------------------------------------------ asyncio callbacks

    def connection_made(self, transport: Any) -> None:
        self.transport = transport
        sock = transport.get_extra_info("socket")
        if sock is not None:
            try:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:
                pass
        peer = transport.get_extra_info("peername")
        self.peer = "%s:%s" % tuple(peer[:2]) if peer else "?"
        transport.set_write_buffer_limits(high=1 << 18)
        # asyncio's selector transport recv()s max_size (256 KiB) bytes per read: allocating
        # that much per small frame costs ~0.1 ms (mmap/munmap); big frames take several reads
        if hasattr(transport, "max_size"):
            transport.max_size = _RECV_SIZE
        # the transport's own non-blocking socket, for try_direct (selector transports)
        self.sock = getattr(transport, "_sock", None)
        self.timer = self.server.loop.call_later(10.0, self._handshake_timeout)

    def data_received(self, data: bytes) -> None:
        self.buf += data
        if not self.open:
            if not self._handshake():
                return
        backend = self.server.backend
        backend.begin_batch()  # the publishes of this read leave in one write per ROS peer
        try:
            self._parse()
        except Exception:  # never let a parser bug leave a half-dead connection
            _log.exception("client %s: frame parser error", self.peer)
            self.close(1011, "internal error")
        finally:
            backend.end_batch()

    def pause_writing(self) -> None:
        self.paused = True

    def resume_writing(self) -> None:
        self.paused = False
        self.flush()

    def connection_lost(self, exc: Optional[Exception]) -> None:
        with self.lock:  # no direct write is in progress once this returns
            self.closing = True  # nothing more is written to this transport
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
        if self.session is not None:
            self.server.closed(self)
        self.open = False

    # ------------------------------------------------------------ handshake

    def _handshake_timeout(self) -> None:
        self.timer = None
        if not self.open:
            self.transport.abort()

    def _reject(self, status: str, text: str) -> None:
        body = (text + "\n").encode()
        self.transport.write(
            (
                "HTTP/1.1 %s\r\nContent-Type: text/plain\r\nContent-Length: %d\r\nConnection: close\r\n\r\n"
                % (status, len(body))
            ).encode()
            + body
        )
        self.transport.close()

    def _handshake(self) -> bool:
        end = self.buf.find(b"\r\n\r\n")
        if end < 0:
            if len(self.buf) > _MAX_HANDSHAKE:
                self._reject("431 Request Header Fields Too Large", "request too large")
            return False
        head = bytes(self.buf[:end]).decode("latin-1")
        del self.buf[: end + 4]
        lines = head.split("\r\n")
        request = lines[0].split(" ")
        headers = {}
        for line in lines[1:]:
            name, sep, value = line.partition(":")
            if sep:
                headers[name.strip().lower()] = value.strip()
        if len(request) != 3 or request[0] != "GET":
            self._reject("400 Bad Request", "expected a WebSocket upgrade request")
            return False
        key = headers.get("sec-websocket-key", "")
        if headers.get("upgrade", "").lower() != "websocket" or "upgrade" not in headers.get("connection", "").lower():
            self._reject("426 Upgrade Required", "this is a rosbridge WebSocket server")
            return False
        if headers.get("sec-websocket-version") != "13" or not key:
            self._reject("400 Bad Request", "unsupported WebSocket version or missing key")
            return False
        accept = base64.b64encode(hashlib.sha1(key.encode("latin-1") + _GUID).digest()).decode()
        self.transport.write(
            (
                "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                "Sec-WebSocket-Accept: %s\r\n\r\n" % accept
            ).encode()
        )
        self.open = True
        if self.timer is not None:
            self.timer.cancel()
        self.server.opened(self)
        self._schedule_ping()
        return True

    # ------------------------------------------------------------ frames in

    def _parse(self) -> None:
        buf = self.buf
        limit = self.server.max_message_size
        while self.open and not self.closing:
            if len(buf) < 2:
                return
            b0, b1 = buf[0], buf[1]
            opcode = b0 & 0x0F
            length = b1 & 0x7F
            pos = 2
            if length == 126:
                if len(buf) < 4:
                    return
                length = struct.unpack_from("!H", buf, 2)[0]
                pos = 4
            elif length == 127:
                if len(buf) < 10:
                    return
                length = struct.unpack_from("!Q", buf, 2)[0]
                pos = 10
            if not b1 & 0x80:
                self.close(1002, "client frames must be masked")
                return
            if b0 & 0x70:
                self.close(1002, "no extension negotiated")
                return
            if opcode >= 8:
                if length > 125 or not b0 & 0x80:
                    self.close(1002, "bad control frame")
                    return
            elif limit and (length > limit or self.parts_size + length > limit):
                self.close(1009, "message larger than max_message_size")
                return
            if len(buf) < pos + 4 + length:
                return
            mask = bytes(buf[pos : pos + 4])
            payload = unmask(bytes(buf[pos + 4 : pos + 4 + length]), mask)
            del buf[: pos + 4 + length]
            self.alive = True
            if opcode >= 8:
                self._control(opcode, payload)
                continue
            if opcode == 0:
                if not self.parts_opcode:
                    self.close(1002, "continuation without a start frame")
                    return
            elif opcode in (1, 2):
                if self.parts_opcode:
                    self.close(1002, "new message inside a fragmented one")
                    return
                self.parts_opcode = opcode
            else:
                self.close(1002, "unknown opcode")
                return
            if not b0 & 0x80:
                self.parts.append(payload)
                self.parts_size += length
                continue
            if self.parts:
                self.parts.append(payload)
                payload = b"".join(self.parts)
                self.parts = []
                self.parts_size = 0
            kind = self.parts_opcode
            self.parts_opcode = 0
            if kind == 1:
                try:
                    message = payload.decode("utf-8")
                except UnicodeDecodeError:
                    message = payload  # the session reports it as garbage; the connection stays
            else:
                message = payload
            self.session.receive(message)

    def _control(self, opcode: int, payload: bytes) -> None:
        if opcode == 9:
            self._write(frame_header(10, len(payload)) + payload)
        elif opcode == 8:
            code = struct.unpack("!H", payload[:2])[0] if len(payload) >= 2 else 1000
            self.close(code if 1000 <= code < 5000 and code not in (1005, 1006, 1015) else 1000, "")
        elif opcode != 10:
            self.close(1002, "unknown control opcode")

    # ------------------------------------------------------------ frames out

    def _write(self, data: bytes) -> None:
        """Loop thread: write data after any unsent rest of a direct write."""
        with self.lock:
            self._write_head()
            self.transport.write(data)

    def _write_head(self) -> None:
        if self.head is not None:
            head, self.head = self.head, None
            self.transport.write(head)

    def flush(self) -> None:
        """Write queued frames until the transport asks to pause."""
        out = self.out
        write = self.transport.write
        with self.lock:
            if self.closing:
                return
            self._write_head()
            # small frames are joined into one write (one send for a burst), big ones
            # are written as they are (no copy)
            parts = []
            size = 0
            while not self.paused and not self.closing:
                frame = out.pop()
                if frame is None:
                    break
                if isinstance(frame, str):
                    data, opcode = frame.encode("utf-8"), 1
                else:
                    data, opcode = frame, 2
                if len(data) < 16384:
                    parts.append(frame_header(opcode, len(data)))
                    parts.append(data)
                    size += len(data)
                    if size < _JOIN_BYTES:
                        continue
                    write(b"".join(parts))
                else:
                    if parts:
                        write(b"".join(parts))
                    write(frame_header(opcode, len(data)))
                    write(data)
                parts = []
                size = 0
            if parts and not self.closing:
                write(b"".join(parts))

    def try_direct(self, message: Any, compression: str) -> bool:
        """Any thread: send a topic frame at once if nothing is queued; True if taken.

        Used by the ROS receive threads to skip the hop to the event loop. Only when the
        client's queue, the transport's buffer and the socket have room is the frame sent
        here (non-blocking); otherwise the caller queues it as usual. So order, the
        bounded queue and the stalled-client guarantees are unchanged: a full socket
        makes this return False, never wait.
        """
        sock = self.sock
        if sock is None or self.paused or self.closing or not self.open:
            return False
        wire = message.wire.get(compression)
        if wire is None:
            wire = message.wire[compression] = wire_frame(message.frame(compression))
        with self.lock:
            if (
                self.closing
                or self.paused
                or self.head is not None
                or len(self.out)
                or self.transport.get_write_buffer_size()
            ):
                return False
            try:
                sent = sock.send(wire)
            except (BlockingIOError, InterruptedError):
                return False
            except OSError:
                return False  # the loop sees the error on its next read or write
            if sent == len(wire):
                return True
            self.head = wire[sent:]
        try:
            self.server.loop.call_soon_threadsafe(self.flush)
        except RuntimeError:  # loop closed
            pass
        return True

    def close(self, code: int = 1000, reason: str = "") -> None:
        """Send a close frame and drop the connection shortly after."""
        if self.closing or self.transport is None:
            return
        self.closing = True
        payload = _close_payload(code, reason)
        try:
            self._write(frame_header(8, len(payload)) + payload)
        except Exception:
            pass
        self.server.loop.call_later(2.0, self.transport.abort)
        self.transport.close()

    def _schedule_ping(self) -> None:
        interval = self.server.ping_interval
        if interval:
            self.timer = self.server.loop.call_later(interval, self._ping)

    def _ping(self) -> None:
        self.timer = None
        if self.closing or not self.open:
            return
        self.alive = False
        self._write(frame_header(9, 0))
        self.timer = self.server.loop.call_later(self.server.ping_timeout or self.server.ping_interval, self._check)

    def _check(self) -> None:
        self.timer = None
        if self.closing or not self.open:
            return
        if not self.alive:
            _log.warning("client %s: no answer to ping, closing", self.peer)
            self.close(1011, "keepalive ping timeout")
            self.transport.abort()
            return
        self._schedule_ping()


class BridgeServer:
    """Serve rosbridge v2 over WebSocket.

    Args:
        loop: The asyncio event loop.
        backend: :class:`rbd_bridge.protocol.Backend`.
        policy: :class:`rbd_bridge.security.Policy`.
        host: Bind address.
        port: TCP port (0 = any free port; see :attr:`port` after :meth:`start`).
        max_message_size: Largest incoming message in bytes (bigger closes with 1009).
        max_queue_frames: Outgoing frames kept per client before the oldest are dropped.
        max_queue_bytes: Outgoing bytes kept per client before the oldest are dropped.
        ping_interval: WebSocket ping period in s (None = off); a client that sends
            nothing within ping_timeout after a ping is disconnected.
        ping_timeout: See ping_interval.
        on_clients: Callable(count) called when the number of clients changes.
        direct_writes: Let other threads send topic frames at once when a client's
            queue is empty (see ``_Connection.try_direct``).
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
        """Configure; nothing listens until start()."""
        self.loop = loop
        self.backend = backend
        self.policy = policy
        self.host = host
        self.port = port
        self.max_message_size = max_message_size
        self.max_queue_frames = max_queue_frames
        self.max_queue_bytes = max_queue_bytes
        self.ping_interval = ping_interval
        self.ping_timeout = ping_timeout
        self.on_clients = on_clients
        self.direct_writes = direct_writes
        self.sessions = {}
        self._connections = {}
        self._ids = itertools.count(1)
        self._server = None

    async def start(self) -> int:
        """Bind and listen; return the port."""
        self._server = await self.loop.create_server(lambda: _Connection(self), self.host, self.port, backlog=128)
        sockets = self._server.sockets or []
        if sockets:
            self.port = sockets[0].getsockname()[1]
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
        if self.on_clients is not None:
            try:
                self.on_clients(len(self.sessions))
            except Exception:
                _log.exception("client count callback failed")

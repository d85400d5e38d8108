"""Reading a TCPROS topic stream (4-byte little-endian length, then the message) on an asyncio loop.

:class:`TcprosFramer` cuts the stream into payloads; :class:`LoopReader` feeds it from a
socket watched by the loop (non-blocking reads in the loop's thread). No rospy, no thread.
"""

import contextlib
import logging
import socket
import struct
from typing import Any, Callable, List, Optional

__all__ = ["FramingError", "LoopReader", "TcprosFramer"]

_log = logging.getLogger("rbd_bridge")
_LEN = struct.Struct("<I")
_MAX_MESSAGE = 1 << 30  # larger than any sane message: a corrupt stream, not data
_READ_SIZE = 65536  # bytes per recv (bigger reads cost an allocation each on this VM)
_READS_PER_WAKEUP = 16  # a burst is read in one wake-up, up to this many recvs


class FramingError(ValueError):
    """The stream is not a TCPROS message stream (absurd length); ``payloads``: the messages before it."""

    def __init__(self, text: str, payloads: List[bytes]) -> None:
        super().__init__(text)
        self.payloads = payloads


class TcprosFramer:
    """Incremental splitter of a TCPROS message stream into payloads (at most max_message bytes each)."""

    def __init__(self, max_message: int = _MAX_MESSAGE) -> None:
        self.max_message = max_message
        self._buf = bytearray()

    @property
    def buffered(self) -> int:
        """Bytes received but not yet part of a complete message."""
        return len(self._buf)

    def feed(self, data: Any) -> List[bytes]:
        """Add data (bytes-like); return the payloads completed by it, in order.

        Raises:
            FramingError: A length above ``max_message`` (the stream is unusable from there on).
        """
        buf = self._buf
        if buf:
            buf += data
            data = buf
        out = []
        pos = 0
        end = len(data)
        unpack = _LEN.unpack_from
        while end - pos >= 4:
            (size,) = unpack(data, pos)
            if size > self.max_message:
                buf.clear()
                raise FramingError("TCPROS message of %d bytes announced" % size, out)
            stop = pos + 4 + size
            if stop > end:
                break
            out.append(bytes(data[pos + 4 : stop]))
            pos = stop
        if data is buf:
            del buf[:pos]
        elif pos < end:
            buf += data[pos:]
        return out


class LoopReader:
    """Read one connected TCPROS topic socket in the event loop's thread (all methods run there).

    The socket (owned, closed by the reader from :meth:`start` on) stays blocking for its
    other users; reads use ``MSG_DONTWAIT`` when the loop reports it readable.
    ``on_messages(payloads)`` gets each batch of complete messages, ``on_close(error or
    None)`` is called once when the stream ends (EOF, socket or framing error, :meth:`stop`).
    """

    def __init__(self, loop: Any, sock: socket.socket, on_messages: Callable, on_close: Callable) -> None:
        self.loop = loop
        self.sock = sock
        self.on_messages = on_messages
        self.on_close = on_close
        self.framer = TcprosFramer()
        self.closed = False
        self.messages = 0
        self._fd = sock.fileno()
        self._view = memoryview(bytearray(_READ_SIZE))

    def start(self) -> None:
        """Watch the socket (raises if the loop cannot)."""
        self.loop.add_reader(self._fd, self._readable)

    def stop(self, error: Optional[BaseException] = None) -> None:
        """Stop watching and close the socket (idempotent); report through on_close."""
        if self.closed:
            return
        self.closed = True
        self.loop.remove_reader(self._fd)  # (False, no error, once the loop is closed)
        with contextlib.suppress(OSError):
            self.sock.close()
        try:
            self.on_close(error)
        except Exception:
            _log.exception("TCPROS reader close callback failed")

    def _readable(self) -> None:
        sock = self.sock
        view = self._view
        for _ in range(_READS_PER_WAKEUP):
            try:
                n = sock.recv_into(view, _READ_SIZE, socket.MSG_DONTWAIT)
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                self.stop(exc)
                return
            if n == 0:
                self.stop(None)
                return
            if not self.feed(view[:n]) or n < _READ_SIZE:
                return

    def feed(self, data: Any) -> bool:
        """Take stream bytes read elsewhere (the handshake's leftover); False once closed."""
        if self.closed:
            return False
        error = None
        try:
            payloads = self.framer.feed(data)
        except FramingError as exc:
            payloads, error = exc.payloads, exc
        if payloads:
            self.messages += len(payloads)
            try:
                self.on_messages(payloads)
            except Exception:
                _log.exception("TCPROS reader message callback failed")
        if error is not None:
            self.stop(error)
        return not self.closed

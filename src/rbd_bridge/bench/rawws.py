"""A minimal blocking WebSocket client (RFC 6455) for benchmarks: low overhead, no threads."""

import base64
import os
import socket
import struct
import sys
import threading
from typing import Any, Optional

# kernel receive timestamps (struct timespec); Python's socket module has no name for it
_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35 if sys.platform.startswith("linux") else 0)


class RawWs:
    """Blocking client: ``send_text``, ``send_binary``, ``recv`` (returns str or bytes)."""

    def __init__(self, host: str, port: int, timeout: Optional[float] = 10.0, rx_stamps: bool = False) -> None:
        """Connect and do the opening handshake.

        With ``rx_stamps``, :attr:`rx_stamp` holds the kernel's receive time (epoch seconds,
        SO_TIMESTAMPNS) of the last segment read, i.e. when the data reached this socket.
        """
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.rx_stamp = None
        self._stamped = bool(rx_stamps and _SO_TIMESTAMPNS)
        if self._stamped:
            self.sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
        key = base64.b64encode(os.urandom(16)).decode()
        request = (
            "GET / HTTP/1.1\r\nHost: %s:%d\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            "Sec-WebSocket-Key: %s\r\nSec-WebSocket-Version: 13\r\n\r\n" % (host, port, key)
        )
        self.sock.sendall(request.encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise ConnectionError("handshake failed")
            head += chunk
        status, _, rest = head.partition(b"\r\n\r\n")
        if b" 101 " not in status.split(b"\r\n")[0]:
            raise ConnectionError(status.decode(errors="replace"))
        self.buf = bytearray(rest)
        self.send_lock = threading.Lock()

    def _send(self, opcode: Any, payload: Any) -> None:
        n = len(payload)
        if n < 126:
            head = struct.pack("!BB", 0x80 | opcode, 0x80 | n)
        elif n < 65536:
            head = struct.pack("!BBH", 0x80 | opcode, 0x80 | 126, n)
        else:
            head = struct.pack("!BBQ", 0x80 | opcode, 0x80 | 127, n)
        # zero mask: valid per RFC 6455 and avoids a Python-speed XOR loop
        with self.send_lock:
            self.sock.sendall(head + b"\x00\x00\x00\x00" + payload)

    def send_text(self, text: str) -> None:
        """Send a text frame."""
        self._send(1, text.encode("utf-8"))

    def send_binary(self, data: Any) -> None:
        """Send a binary frame."""
        self._send(2, bytes(data))

    def _read(self, size: int) -> bytes:
        if not self._stamped:
            return self.sock.recv(size)
        chunk, ancillary, _flags, _addr = self.sock.recvmsg(size, 64)
        for level, kind, data in ancillary:
            if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(data) >= 16:
                secs, nsecs = struct.unpack("qq", data[:16])
                self.rx_stamp = secs + nsecs * 1e-9
        return chunk

    def _need(self, n: int) -> None:
        while len(self.buf) < n:
            chunk = self._read(max(65536, n - len(self.buf)))
            if not chunk:
                raise ConnectionError("connection closed")
            self.buf += chunk

    def recv(self) -> Any:
        """Return the next data frame (str for text, bytes for binary); answers pings."""
        message = bytearray()
        first_opcode = None
        while True:
            self._need(2)
            b0, b1 = self.buf[0], self.buf[1]
            n = b1 & 0x7F
            pos = 2
            if n == 126:
                self._need(4)
                n = struct.unpack("!H", bytes(self.buf[2:4]))[0]
                pos = 4
            elif n == 127:
                self._need(10)
                n = struct.unpack("!Q", bytes(self.buf[2:10]))[0]
                pos = 10
            self._need(pos + n)
            payload = bytes(self.buf[pos : pos + n])
            del self.buf[: pos + n]
            opcode = b0 & 0x0F
            if opcode == 9:
                self._send(10, payload)
                continue
            if opcode == 8:
                raise ConnectionError("closed by server: %r" % payload[2:])
            if opcode == 10:
                continue
            if first_opcode is None:
                first_opcode = opcode
            message += payload
            if b0 & 0x80:
                break
        return bytes(message).decode("utf-8") if first_opcode == 1 else bytes(message)

    def close(self) -> None:
        """Close the TCP connection (no closing handshake)."""
        try:
            self.sock.close()
        except OSError:
            pass

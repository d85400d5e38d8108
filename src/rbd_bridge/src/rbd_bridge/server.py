"""asyncio WebSocket transport: one :class:`rbd_bridge.protocol.Session` per connection.

Uses the ``websockets`` library: its newer asyncio implementation
(``websockets.asyncio.server``, websockets >= 13, about half the per-frame overhead of the
legacy one) when present, else the long-standing ``websockets.serve`` (the Python 3.6-era
releases). Per-message deflate is off: it costs far more CPU than it saves on
loopback/LAN for JSON frames.
"""

import asyncio
import itertools
import logging
import os
from typing import Any, Callable

import websockets

try:
    from websockets.asyncio.server import serve as _serve

    if os.environ.get("RBD_WS_LEGACY"):
        _serve = websockets.serve
except ImportError:  # websockets < 13 (Python 3.6 robots)
    _serve = websockets.serve

from rbd_bridge.protocol import OutQueue, Session

__all__ = ["BridgeServer"]

_log = logging.getLogger("rbd_bridge")


class BridgeServer:
    """Serve rosbridge v2 over WebSocket.

    Args:
        loop: The asyncio event loop.
        backend: :class:`rbd_bridge.protocol.Backend`.
        policy: :class:`rbd_bridge.security.Policy`.
        host: Bind address.
        port: TCP port (0 = any free port; see :attr:`port` after :meth:`start`).
        max_message_size: Largest incoming frame in bytes (bigger closes with 1009).
        max_queue_frames: Outgoing frames kept per client before the oldest are dropped.
        max_queue_bytes: Outgoing bytes kept per client before the oldest are dropped.
        ping_interval: WebSocket ping period in s (None = off); a client that does not
            answer within ping_timeout is disconnected.
        ping_timeout: See ping_interval.
        on_clients: Callable(count) called when the number of clients changes.
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
        ping_interval: float = 20.0,
        ping_timeout: float = 20.0,
        on_clients: Callable[..., Any] = None,
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
        self.sessions = {}
        self._ids = itertools.count(1)
        self._server = None

    async def start(self) -> Any:
        """Bind and listen; returns when the socket is open."""
        self._server = await _serve(
            self._handle,
            self.host,
            self.port,
            max_size=self.max_message_size,
            max_queue=8,
            compression=None,
            ping_interval=self.ping_interval,
            ping_timeout=self.ping_timeout,
            write_limit=2**18,
            close_timeout=2,
        )
        sockets = self._server.sockets or []
        if sockets:
            self.port = sockets[0].getsockname()[1]
        return self.port

    async def stop(self) -> None:
        """Close every connection and the listening socket."""
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None

    def _closer(self, ws: Any) -> Any:
        def close(code: int, reason: str) -> None:
            asyncio.ensure_future(ws.close(code, reason))

        return close

    async def _handle(self, ws: Any, path: str = None) -> None:
        client_id = next(self._ids)
        peer = "%s:%s" % tuple(ws.remote_address[:2]) if ws.remote_address else "?"
        wake = asyncio.Event()
        out = OutQueue(self.max_queue_frames, self.max_queue_bytes, notify=wake.set)
        session = Session(
            client_id, self.backend, self.policy, out, self.loop.call_later, close=self._closer(ws), peer=peer
        )
        session.max_message_size = self.max_message_size
        self.sessions[client_id] = session
        self._clients_changed()
        _log.info("client %d connected from %s (%d connected)", client_id, peer, len(self.sessions))
        writer = asyncio.ensure_future(self._write(ws, out, wake))
        try:
            async for data in ws:
                session.receive(data)
        except websockets.ConnectionClosed:
            pass
        except Exception:
            _log.exception("client %d: transport error", client_id)
        finally:
            writer.cancel()
            session.close()
            self.sessions.pop(client_id, None)
            self._clients_changed()
            if out.dropped:
                _log.warning("client %d: %d outgoing frames dropped (slow client)", client_id, out.dropped)
            _log.info("client %d disconnected (%d connected)", client_id, len(self.sessions))

    def _clients_changed(self) -> None:
        if self.on_clients is not None:
            try:
                self.on_clients(len(self.sessions))
            except Exception:
                _log.exception("client count callback failed")

    @staticmethod
    async def _write(ws: Any, out: Any, wake: Any) -> None:
        try:
            while True:
                frame = out.pop()
                if frame is None:
                    wake.clear()
                    await wake.wait()
                    continue
                await ws.send(frame)
        except (websockets.ConnectionClosed, asyncio.CancelledError):
            pass

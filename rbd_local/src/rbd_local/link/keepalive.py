"""The link's keep-alive: WebSocket pings that find a link gone silent without closing.

Every ``keepalive_s / 5`` the link thread has the reactor send a WebSocket ping; a connection that
answers nothing (no pong, no message) for ``keepalive_s`` after a ping went out is dropped.
autobahn's built-in auto-ping was used before; in about one test-suite run in two its first ping
was never scheduled and a silent link stayed "connected". The time is counted from the ping the
reactor actually sent, and the verdict is the reactor's, after it has read its socket: a laptop
too busy to run this process for a while (the reactor starved) must not take its own stall for
the robot's silence. The silence must also span :data:`KEEPALIVE_PINGS` pings sent one cadence
apart (a stalled reactor never has more than one ping queued): a stall of the whole process that
ends just before the verdict is due leaves no time for the answer, which the in-process peer of
CI's niced tests sent late for the same stall.

Threads: :meth:`KeepAlive.tick` runs on the link thread, everything else on Twisted's reactor
thread (roslibpy's transport on CPython).
"""

import logging
import time
from typing import Callable

LOG = logging.getLogger("rbd_local.link")

#: A silent link is dropped only after this many unanswered pings went out (one per keepalive_s / 5).
KEEPALIVE_PINGS = 4


class KeepAlive:
    """Pings one connection at a time and drops it when it stays silent."""

    def __init__(self, keepalive_s: float, address: str, on_silent: Callable[[], None]) -> None:
        """Configure it (nothing is watched until :meth:`watch`).

        Args:
            keepalive_s: silence [s] after a ping before the connection is dropped (0: off).
            address: the bridge's address, for the log.
            on_silent: called on the reactor thread just before a silent connection is dropped.
        """
        self.keepalive_s = float(keepalive_s)
        self.address = address
        self._on_silent = on_silent
        self._alive = None  # the connection's protocol while it is watched
        self.unanswered = None  # type: Optional[float]  # when the first unanswered ping went out (reactor)
        self._pings = 0  # pings sent since then (reactor thread)
        self._ping_queued = False  # a ping handed to the reactor and not yet sent
        self._next_ping = 0.0
        self.pings_sent = 0  # every ping sent, on any connection (a proof for tests and logs)

    def watch(self, proto: object) -> None:
        """Watch the connection of this autobahn protocol (None or no ping support: nothing)."""
        self._alive = None
        self.unanswered = None
        if self.keepalive_s <= 0 or proto is None or not hasattr(proto, "sendPing"):
            return

        def heard() -> None:  # reactor thread
            self.unanswered = None
            self._pings = 0

        on_pong, on_message = proto.onPong, proto.onMessage

        def pong(payload: bytes) -> None:
            heard()
            on_pong(payload)

        def message(payload: bytes, is_binary: bool) -> None:
            heard()
            on_message(payload, is_binary)

        proto.onPong = pong
        proto.onMessage = message
        self._next_ping = 0.0
        self._ping_queued = False
        self._alive = proto

    def forget(self) -> None:
        """Stop watching (the connection is being torn down)."""
        self._alive = None

    def tick(self, now: float) -> None:
        """Link thread: have the reactor send the next ping when it is due."""
        proto = self._alive
        if proto is None or now < self._next_ping or self._ping_queued:
            return
        from twisted.internet import reactor  # roslibpy's transport on CPython

        self._ping_queued = True  # _ping sets the next ping's time when it has sent this one
        reactor.callFromThread(self._ping, proto)

    def _ping_period(self) -> float:
        return max(0.2, self.keepalive_s / 5.0)

    def _ping(self, proto: object) -> None:
        """Reactor thread: send a ping; the first unanswered one starts the silence clock."""
        self._ping_queued = False
        if proto is not self._alive:
            return
        proto.sendPing()
        self.pings_sent += 1
        self._next_ping = time.monotonic() + self._ping_period()  # the cadence of pings actually sent
        self._pings = 1 if self.unanswered is None else self._pings + 1
        if self.unanswered is None:
            from twisted.internet import reactor

            sent = self.unanswered = time.monotonic()
            reactor.callLater(self.keepalive_s, self._judge, proto, sent, sent + self.keepalive_s)

    def _judge(self, proto: object, sent: float, due: float) -> None:
        """Reactor thread: drop the connection if the ping sent at ``sent`` is still unanswered."""
        if proto is not self._alive or self.unanswered != sent:
            return  # answered, or another connection by now
        from twisted.internet import reactor

        now = time.monotonic()
        if now - due > 0.25 or self._pings < KEEPALIVE_PINGS:
            # This verdict comes late (the reactor itself was stalled, and whatever arrived meanwhile
            # is still unread), or this process ran too little of the time to send its pings: read
            # what came, send one more ping, and give the robot one more cadence of our own time.
            wait = self._ping_period()
            reactor.callLater(wait, self._judge, proto, sent, now + wait)
            return
        LOG.warning("link to %s silent: no answer to a ping for %.1f s; dropping it", self.address, now - sent)
        self._alive = None
        self._on_silent()
        proto.dropConnection(True)

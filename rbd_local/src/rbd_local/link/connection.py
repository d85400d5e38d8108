"""One roslibpy connection to the bridge: opened without roslibpy's own retry, abandoned, closed.

Reconnection is the link's own (a fresh client per attempt), so each client's factory has its
Twisted retry switched off (``continueTrying``, a public attribute of Twisted's
ReconnectingClientFactory). ``factory.stopTrying()`` would also stop the connector, which roslibpy
has already handed to the reactor thread: from the link thread that raced with the reactor (a
KeyError in epoll killed the link thread in one test run) or aborted the attempt.

Every client of the process shares one roslibpy event-loop manager: each new manager would start
another Twisted log observer, and a link that retries every second for hours would pile them up.
roslibpy 2.1 has no public hook for that (``factory.manager`` is a read-only property that makes a
manager on first use), so the shared one is put into the factory's ``_manager``.
"""

import logging
from typing import Optional

import roslibpy

LOG = logging.getLogger("rbd_local.link")

_shared_manager = None


def open_client(host: str, port: int, timeout: float) -> Optional["roslibpy.Ros"]:
    """A connected roslibpy client, or None if it did not connect within ``timeout`` [s].

    A failed attempt is abandoned (see :func:`abandon`), so it never opens later.
    """
    global _shared_manager
    ros = roslibpy.Ros(host, port)
    ros.factory.continueTrying = 0
    if _shared_manager is not None and hasattr(ros.factory, "_manager"):
        ros.factory._manager = _shared_manager
    else:
        _shared_manager = ros.factory.manager
    try:
        ros.run(timeout=timeout)
    except Exception as exc:
        LOG.debug("cannot connect to ws://%s:%d: %s", host, port, exc)
        abandon(ros)
        return None
    return ros


def protocol(ros: "roslibpy.Ros") -> object:
    """The client's autobahn WebSocket protocol (what the keep-alive pings), or None."""
    return getattr(ros.factory, "_proto", None)


def abandon(ros: "roslibpy.Ros") -> None:
    """An attempt that timed out: stop it in the reactor, so that it never opens later.

    A slow handshake would otherwise complete after the next attempt started, and every
    retry on a slow network would leave one more open connection behind.
    """
    from twisted.internet import reactor

    factory = ros.factory

    def stop() -> None:
        if factory.connector is not None:
            factory.connector.disconnect()  # connecting: stop; connected: close the transport

    reactor.callFromThread(stop)


def close_quietly(ros: "roslibpy.Ros") -> None:
    """Close a client; errors are logged, never raised."""
    try:
        ros.factory.stopTrying()
        if ros.is_connected:
            ros.close(timeout=1.0)
    except Exception:
        LOG.debug("closing the old connection failed", exc_info=True)

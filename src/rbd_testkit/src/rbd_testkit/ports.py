"""TCP ports on 127.0.0.1: one that is free now, and waiting until something listens on one."""

import random
import socket
import subprocess
import time
from typing import Optional, Set, Tuple

LOCALHOST = "127.0.0.1"

#: Where ``free_port`` picks: below the rostests' bridge ports (20000-31999, their launch files)
#: and below the kernel's ephemeral range (net.ipv4.ip_local_port_range, 32768-60999 by default).
#: Every bind to port 0 on the machine (each ROS node's XML-RPC and TCPROS servers) and every
#: outgoing connection draw from the ephemeral range at any time: a port found free there can be
#: taken by another process's node before the caller's server binds it (EADDRINUSE).
PORT_RANGE = (10000, 20000)
_RNG = random.SystemRandom()  # not the random module: pytest-randomly seeds that alike in both test lanes
_given: Set[int] = set()  # handed out by this process (their servers may not listen yet)


def _ephemeral_range() -> Tuple[int, int]:
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as fh:
            low, high = (int(v) for v in fh.read().split())
        return low, high
    except (OSError, ValueError):
        return 32768, 60999


def free_port(host: str = LOCALHOST) -> int:
    """Return a TCP port on ``host`` that is free right now, outside the kernel's ephemeral range.

    A random port of ``PORT_RANGE`` (never one this process returned before) that binds now; the
    socket is closed again, so another process could still take it before the caller does, but
    only one that picks its port itself as this does (ROS nodes' servers and outgoing connections
    take ephemeral ports). If the machine's ephemeral range covers ``PORT_RANGE``, the kernel
    picks (port 0). Tests never assume 11311 or 9090 are free.

    Args:
        host: address to bind on.

    Returns:
        The port number.

    Example:
        >>> port = free_port()
    """
    low, high = PORT_RANGE
    eph_low, eph_high = _ephemeral_range()
    if eph_low < high and low <= eph_high:
        high = min(high, eph_low)
    for _ in range(200 if high > low else 0):
        port = _RNG.randrange(low, high)
        if port in _given:
            continue
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            try:
                s.bind((host, port))
            except OSError:
                continue
        _given.add(port)
        return port
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def wait_for_port(
    port: int,
    timeout: float = 20.0,
    host: str = LOCALHOST,
    proc: Optional[subprocess.Popen] = None,
    step: float = 0.05,
) -> None:
    """Block until something accepts TCP connections on ``host:port``.

    Args:
        port: TCP port.
        timeout: seconds to wait at most.
        host: address to connect to.
        proc: the process expected to listen; when it exits first, stop waiting at once.
        step: pause between two attempts [s].

    Raises:
        TimeoutError: nothing listens after ``timeout`` seconds.
        RuntimeError: ``proc`` exited before anything listened.

    Example:
        >>> wait_for_port(env.port, timeout=30.0, proc=env.master)  # doctest: +SKIP
    """
    deadline = time.monotonic() + timeout
    while True:
        try:
            with socket.create_connection((host, port), timeout=0.5):
                return
        except OSError:
            pass
        if proc is not None and proc.poll() is not None:
            raise RuntimeError("process %d exited with %s before anything listened on port %d"
                               % (proc.pid, proc.returncode, port))
        if time.monotonic() >= deadline:
            raise TimeoutError("nothing listens on %s:%d after %.0f s" % (host, port, timeout))
        time.sleep(step)

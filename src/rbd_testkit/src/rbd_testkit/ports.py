"""TCP ports on 127.0.0.1: one that is free now, and waiting until something listens on one."""

import socket
import subprocess
import time
from typing import Optional

LOCALHOST = "127.0.0.1"


def free_port(host: str = LOCALHOST) -> int:
    """Return a TCP port on ``host`` that is free right now.

    The kernel picks the port (bind to port 0); the socket is closed again, so another process
    could take it before the caller does. Tests never assume 11311 or 9090 are free.

    Args:
        host: address to bind on.

    Returns:
        The port number.

    Example:
        >>> port = free_port()
    """
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

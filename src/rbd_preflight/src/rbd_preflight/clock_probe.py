"""The clock of another ROS host, read without any extra daemon (issue 16, preflight; no ROS imports).

Every ROS graph already runs HTTP servers on each of its hosts: the XML-RPC servers of the master,
of every roslaunch (``split.launch`` starts one per machine) and of every rospy node. Python's HTTP
server puts a ``Date`` header into every response, the server's wall clock truncated to the whole
second (RFC 7231; ``email.utils.formatdate``). One reply bounds the server's clock to a one-second
window; a reply just before and one just after the server's clock turns to the next second bound
it as tightly as the requests are spaced, the method of ``htpdate``:

    a reply with Date D, sent at local t_send and received at local t_recv, was written when the
    server's clock read D + f (0 <= f < 1) at some local instant in [t_send, t_recv], so
    offset = server - local lies in [D - t_recv, D + 1 - t_send].

:func:`measure` intersects these intervals while it places requests around the predicted next
turn of the second: the result is the interval's midpoint with half its width as the
uncertainty, about one round trip (loopback ~1 ms, a WLAN 2-20 ms). C++ nodes (roscpp's XmlRpc++)
send no Date header; a host that runs only those and no roslaunch cannot be read this way.
"""

import calendar
import email.utils
import http.client
import math
import time
from typing import Callable, List, Optional, Sequence, Tuple
from urllib.parse import urlparse

#: (t_send, t_recv, server second) of one reply.
Sample = Tuple[float, float, int]

_BODY = (
    b"<?xml version='1.0'?><methodCall><methodName>getPid</methodName><params><param><value><string>/preflight"
    b"</string></value></param></params></methodCall>"
)


class NoDateHeaderError(Exception):
    """The server answered without a Date header (e.g. a roscpp node)."""


def offset_bounds(samples: Sequence[Sample]) -> Tuple[float, float]:
    """The interval [lo, hi] that every sample allows for ``server clock - local clock`` [s].

    Raises:
        ValueError: without samples, or if they contradict each other (a clock that jumped).
    """
    if not samples:
        raise ValueError("no samples")
    lo = max(d - t_recv for t_send, t_recv, d in samples)
    hi = min(d + 1.0 - t_send for t_send, t_recv, d in samples)
    if lo > hi:
        raise ValueError("samples contradict each other (did a clock jump?)")
    return lo, hi


def parse_date(value: str) -> int:
    """Seconds since the epoch of an HTTP Date header (``Tue, 15 Nov 1994 08:12:31 GMT``)."""
    parsed = email.utils.parsedate_tz(value)
    if parsed is None:
        raise ValueError("not an HTTP date: %r" % value)
    return int(calendar.timegm(parsed[:9]) - (parsed[9] or 0))


def http_date_sampler(url: str, timeout: float = 2.0, clock: Callable[[], float] = time.time) -> Callable[[], Sample]:
    """A function that POSTs one XML-RPC ``getPid`` to ``url`` and returns its :data:`Sample`.

    The connection is made before ``t_send`` is taken, so only the request and its answer fall
    inside the bracket.
    """
    parts = urlparse(url)
    host, port = parts.hostname, parts.port or 80
    path = parts.path or "/"

    def sample() -> Sample:
        conn = http.client.HTTPConnection(host, port, timeout=timeout)
        try:
            conn.connect()
            t_send = clock()
            conn.request("POST", path, body=_BODY, headers={"Content-Type": "text/xml"})
            response = conn.getresponse()
            t_recv = clock()
            date = response.getheader("Date")
            response.read()
        finally:
            conn.close()
        if not date:
            raise NoDateHeaderError("%s sends no Date header" % url)
        return t_send, t_recv, parse_date(date)

    return sample


def measure(sample: Callable[[], Sample], target: float = 0.004, budget: float = 3.0, coarse_step: float = 0.05,
            clock: Callable[[], float] = time.time,
            sleep: Callable[[float], None] = time.sleep) -> Tuple[float, float, List[Sample]]:
    """Offset of a server's clock from ``clock`` [s]: (estimate, uncertainty, samples used).

    First requests every ``coarse_step`` until the server's second turns (at most ~1 s), then
    requests back to back from the start of each predicted next turn's window until a reply shows
    the turn, until the uncertainty is below ``target`` or ``budget`` seconds have passed.

    Raises:
        NoDateHeaderError: if the server sends no Date header.
        OSError: if the server cannot be reached.
    """
    start = clock()
    samples = [sample()]
    # coarse: until the server's second has turned once between two replies
    while clock() - start < budget and len({d for _s, _r, d in samples}) < 2:
        sleep(coarse_step)
        samples.append(sample())
    # fine: the server's clock turns to the whole second N at local N - offset, somewhere in
    # [N - hi, N - lo]: ask back to back from the window's start until a reply shows the turn
    while clock() - start < budget:
        lo, hi = offset_bounds(samples)
        if (hi - lo) / 2.0 <= target:
            break
        turn = math.ceil(clock() + hi + 0.01)  # the next N whose window still lies ahead
        first, last = turn - hi - 0.002, turn - lo + 0.002
        wait = first - clock()
        if wait > 0:
            sleep(wait)
        while clock() <= last and clock() - start < budget:
            samples.append(sample())
            if samples[-1][2] >= turn:
                break
    lo, hi = offset_bounds(samples)
    return (lo + hi) / 2.0, (hi - lo) / 2.0, samples


def measure_host(urls: Sequence[str], budget: float = 3.0, target: float = 0.004,
                 clock: Callable[[], float] = time.time) -> Tuple[float, float, str]:
    """Offset of the first of ``urls`` (one host's XML-RPC servers) that sends a Date header.

    Returns:
        (offset [s], uncertainty [s], url used).

    Raises:
        NoDateHeaderError: if none of them does (the text lists what was tried).
    """
    tried = []  # type: List[str]
    for url in urls:
        try:
            offset, uncertainty, _ = measure(http_date_sampler(url, clock=clock), target=target, budget=budget,
                                             clock=clock)
            return offset, uncertainty, url
        except (NoDateHeaderError, OSError, ValueError, http.client.HTTPException) as exc:
            tried.append("%s: %s" % (url, exc))
    detail = (": " + "; ".join(tried)) if tried else ""
    raise NoDateHeaderError("no Date header from %d server(s)%s" % (len(tried), detail))


def host_of(uri: Optional[str]) -> Optional[str]:
    """Host part of an XML-RPC URI (``http://host:port/``)."""
    if not uri:
        return None
    return urlparse(uri).hostname


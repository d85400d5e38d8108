"""The ROS backend of the sessions: topics (:mod:`rbd_bridge.ros.topics`), services, rosapi.

Its methods run on the event loop thread; blocking ROS calls run in the services' pool.
"""

from typing import Any

import rospy

from rbd_bridge.core.rosapi import RosApi
from rbd_bridge.ros.fastpath import FastPath, rospy_unfit
from rbd_bridge.ros.graph import RosParams, RosTypes, ThreadLocalMaster
from rbd_bridge.ros.services import Services
from rbd_bridge.ros.topics import Topics

__all__ = ["RosBackend"]


def _now() -> Any:
    t = rospy.get_rostime()
    return t.secs, t.nsecs


class RosBackend:
    """rospy implementation of the session backend (see :mod:`rbd_bridge.core.session`).

    Args:
        loop: The asyncio loop the sessions live on.
        policy: The bridge's :class:`rbd_bridge.core.security.Policy` (rosapi filtering).
        service_timeout: Seconds a ROS caller waits for a client-hosted service.
        call_timeout: Default seconds for ``call_service`` without ``timeout`` (0 = none).
        fast_path: Use :mod:`rbd_bridge.ros.fastpath` (patches rospy internals; faster) if they fit.
        direct_reads: With the fast path: read subscribed connections in the event loop.
        fail_direct_reads: Test hook: every take-over fails (rospy's threads read).
        advertise_window: Seconds after advertise whose publishes reach subscribers still
            connecting (0 = off).
        publisher_linger: Seconds a publisher stays registered after its last client left.
    """

    def __init__(
        self,
        loop: Any,
        policy: Any,
        service_timeout: float = 10.0,
        call_timeout: float = 30.0,
        fast_path: bool = True,
        direct_reads: bool = True,
        fail_direct_reads: bool = False,
        advertise_window: float = 1.0,
        publisher_linger: float = 5.0,
    ) -> None:
        """Create the backend (rospy.init_node must have been called)."""
        master = ThreadLocalMaster(rospy.get_name())
        self.topics = Topics(loop, master, advertise_window, None, publisher_linger)
        unfit = fast_path and rospy_unfit()
        if unfit:  # one line, then plain rospy
            rospy.logwarn("rbd_bridge: ~rospy_fast_path off: rospy's internals differ (%s); plain rospy", unfit)
        elif fast_path:
            self.topics.fast = FastPath(loop, self.topics.subs.get, direct_reads, fail_direct_reads)
        self.fast = self.topics.fast
        self.services = Services(loop, master, service_timeout, call_timeout)
        self.services.rosapi = RosApi(policy, master, RosParams(), _now, self.services.service_type, RosTypes())
        for name in ("advertise", "unadvertise", "publish", "subscribe", "unsubscribe"):
            setattr(self, name, getattr(self.topics, name))
        for name in ("call_service", "advertise_service", "unadvertise_service", "service_response"):
            setattr(self, name, getattr(self.services, name))
        self.begin_batch = self.fast.begin_batch if self.fast else lambda: None
        self.end_batch = self.fast.end_batch if self.fast else lambda: None

    def session_closed(self, session: Any) -> None:
        """Release publishers, subscriptions and hosted services of a gone client."""
        self.topics.release(session)
        self.services.release(session)

    def stats(self) -> dict:
        """Counters of the receive paths (for the node's ``~stats``)."""
        stats = self.fast.stats() if self.fast else dict.fromkeys(FastPath.COUNTERS + ("direct_read_open",), 0)
        stats["direct_reads"] = bool(self.fast and self.fast.direct_reads)
        stats["rospy_fast_path"] = self.fast is not None
        stats["rospy_read_messages"] = self.topics.rospy_read_messages
        return stats

    def shutdown(self) -> None:
        """Stop everything (node exit)."""
        if self.fast is not None:
            self.fast.shutdown()
        self.services.shutdown()

"""The robot link: the only module of rbd_local that imports roslibpy.

Everything the laptop app exchanges with the robot goes through :class:`RobotLink`, which
talks to ``rbd_bridge`` (rosbridge v2 protocol) from its own background thread:

- publishes ``/rbd_gestrec/gesture`` (std_msgs/String, the trick command) and the operator
  heartbeat ``/rbd_local/heartbeat`` (std_msgs/Header, ~2 Hz);
- calls ``/rbd_controller/em_stop`` (std_srvs/SetBool);
- subscribes ``/rbd_pos_controller/status``, ``/rbd_controller/state`` (std_msgs/String) and
  ``/rbd_controller/path_queue`` (rbd_msgs/PathQueue) and hands them to callbacks;
- optionally subscribes the robot's camera (sensor_msgs/CompressedImage, by default the
  ZED2's left image ``/zed2/zed_node/left/image_rect_color/compressed``), throttled by the
  bridge, newest frame only;
- reads the robot's tricks (``/rbd_navigation/tricks`` through rosapi) for teach mode;
- runs the robot's preflight (``/preflight/run``, rbd_msgs/RunPreflight) and subscribes its
  latched last report ``/preflight/report`` (rbd_msgs/PreflightReport) for the Preflight panel.

Callers never block on the network: :meth:`RobotLink.send_gesture` only queues. A lost link
is re-established by the background thread (a fresh connection every ``retry_s``); gestures
are never queued across a link loss (a stale "walk" must not move the robot later), they are
dropped and counted instead. A link that goes silent without closing (WLAN out of range) is
found by WebSocket pings (``keepalive_s``) and dropped.
"""

import concurrent.futures
import logging
import queue
import threading
import time
from typing import Callable

import roslibpy
from roslibpy.core import RosTimeoutError

LOG = logging.getLogger("rbd_local.link")

GESTURE_TOPIC = "/rbd_gestrec/gesture"
HEARTBEAT_TOPIC = "/rbd_local/heartbeat"
EM_STOP_SERVICE = "/rbd_controller/em_stop"
STATUS_TOPIC = "/rbd_pos_controller/status"
STATE_TOPIC = "/rbd_controller/state"
PATH_QUEUE_TOPIC = "/rbd_controller/path_queue"
#: The ZED2 wrapper's left image through image_transport's compressed plugin.
CAMERA_TOPIC = "/zed2/zed_node/left/image_rect_color/compressed"
CAMERA_TYPE = "sensor_msgs/CompressedImage"
#: rbd_navigation's tricks (its private parameter, loaded from config/tricks.yaml).
TRICKS_PARAM = "/rbd_navigation/tricks"
#: rbd_bringup's preflight_server (node ``/preflight``): runs the checks on demand (read-only).
PREFLIGHT_SERVICE = "/preflight/run"
PREFLIGHT_SERVICE_TYPE = "rbd_msgs/RunPreflight"
#: The last report, latched.
PREFLIGHT_TOPIC = "/preflight/report"
PREFLIGHT_TYPE = "rbd_msgs/PreflightReport"
PREFLIGHT_STATUSES = ("PASS", "FAIL", "SKIP")
PREFLIGHT_MAX_DURATION_S = 10.0
#: A silent link is dropped only after this many unanswered pings went out (one per keepalive_s / 5).
KEEPALIVE_PINGS = 4


def tricks_from_param(value: object) -> dict:
    """The trick names and their steps' names from the value of ``/rbd_navigation/tricks``.

    Args:
        value: the parameter as rosapi returns it: {trick: [{"name": ..., "x": ..., ...}]}.

    Returns:
        {trick: [step name, ...]} in the parameter's order.

    Raises:
        ValueError: when the value does not have that shape.
    """
    if not isinstance(value, dict) or not value:
        raise ValueError("%s is not a mapping of tricks: %r" % (TRICKS_PARAM, value))
    out = {}
    for name, steps in value.items():
        if not isinstance(steps, list) or not steps:
            raise ValueError("%s/%s is not a list of steps" % (TRICKS_PARAM, name))
        names = []
        for i, step in enumerate(steps):
            if not isinstance(step, dict) or not isinstance(step.get("name"), str):
                raise ValueError("%s/%s[%d] has no name" % (TRICKS_PARAM, name, i))
            names.append(step["name"])
        out[str(name)] = names
    return out


def _stamp_seconds(stamp: object) -> float:
    if not isinstance(stamp, dict):
        raise ValueError("header.stamp is not a time: %r" % (stamp,))
    secs, nsecs = stamp.get("secs"), stamp.get("nsecs", 0)
    if not isinstance(secs, int) or not isinstance(nsecs, int):
        raise ValueError("header.stamp is not a time: %r" % (stamp,))
    return secs + nsecs * 1e-9


def preflight_report_from_msg(msg: object) -> dict:
    """A preflight report as the GUI shows it, from an rbd_msgs/PreflightReport message dict.

    Args:
        msg: the message as rosbridge sends it (``header``, ``ready``, ``duration``,
            ``checks``: [{``key``, ``name``, ``status``, ``value``, ``hint``}], ``mounts``,
            ``mounts_file``).

    Returns:
        {"ready": bool, "stamp": float (POSIX seconds, end of the observation; 0 if unset),
        "duration": float [s], "checks": [{"key", "name", "status", "value", "hint"}] in the
        robot's order, "mounts": [str], "mounts_file": str}.

    Raises:
        ValueError: when the message does not have that shape or a status is not PASS/FAIL/SKIP.
    """
    if not isinstance(msg, dict):
        raise ValueError("preflight report is not a message: %r" % (msg,))
    header = msg.get("header")
    stamp = _stamp_seconds(header.get("stamp") if isinstance(header, dict) else None)
    rows = msg.get("checks")
    if not isinstance(rows, list) or not isinstance(msg.get("ready"), bool):
        raise ValueError("preflight report without ready/checks: %r" % (msg,))
    checks = []
    for i, row in enumerate(rows):
        if not isinstance(row, dict):
            raise ValueError("preflight check %d is not a message" % i)
        fields = {k: row.get(k, "") for k in ("key", "name", "status", "value", "hint")}
        if not all(isinstance(v, str) for v in fields.values()) or fields["status"] not in PREFLIGHT_STATUSES:
            raise ValueError("preflight check %d is malformed: %r" % (i, row))
        checks.append(fields)
    mounts = msg.get("mounts", [])
    try:
        duration = float(msg.get("duration", 0.0))
    except (TypeError, ValueError):
        duration = None
    if duration is None or not isinstance(mounts, list):
        raise ValueError("preflight report has a bad duration or mounts: %r" % (msg,))
    return {"ready": msg["ready"], "stamp": stamp, "duration": duration, "checks": checks,
            "mounts": [str(m) for m in mounts], "mounts_file": str(msg.get("mounts_file", ""))}


class RobotLink:
    """Background connection to the robot's rosbridge server."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 9090,
        heartbeat_hz: float = 2.0,
        retry_s: float = 1.0,
        connect_timeout_s: float = 2.0,
        gesture_max_age_s: float = 0.5,
        keepalive_s: float = 5.0,
        on_status: Callable[[str], None] = None,
        on_state: Callable[[str], None] = None,
        on_path_queue: Callable[[list], None] = None,
        on_connection: Callable[[bool], None] = None,
        on_camera: Callable[[dict], None] = None,
        camera_topic: str = CAMERA_TOPIC,
        camera_throttle_ms: int = 0,
        on_preflight: Callable[[dict], None] = None,
    ) -> None:
        """Configure the link (call :meth:`start` to connect).

        Args:
            host: bridge host name or address.
            port: bridge port.
            heartbeat_hz: heartbeat rate (0 disables it).
            retry_s: pause between connection attempts [s].
            connect_timeout_s: time allowed for one connection attempt [s].
            gesture_max_age_s: queued gestures older than this are dropped, not sent [s].
            keepalive_s: a link silent about this long is dropped and re-established [s]
                (0 disables): a WebSocket ping goes out every keepalive_s / 5 and the
                connection is dropped when nothing (pong or message) has come back for
                keepalive_s after a ping was sent and while four pings in all went out
                (counted from the pings' actual sending, so a stall of this process is not
                taken for the robot's silence). Over a WLAN
                that goes silent the TCP connection stays "open"; without this, requests
                written into it (an e-stop) would be delivered whenever it came back.
            on_status: called with each ``/rbd_pos_controller/status`` string.
            on_state: called with each ``/rbd_controller/state`` string.
            on_path_queue: called with the ``names`` list of each path-queue message.
            on_connection: called with True/False when the link comes up / goes down.
            on_camera: called with each camera message (a dict with ``header``, ``format``
                and base64 ``data``, as the bridge sends sensor_msgs/CompressedImage); None:
                no camera subscription.
            camera_topic: the camera's CompressedImage topic.
            camera_throttle_ms: least time between camera messages the bridge sends [ms]
                (0: every one); the bridge keeps only the newest frame for a slow link.
            on_preflight: called with each report of the latched ``/preflight/report`` (the
                last one arrives right after every connection), as
                :func:`preflight_report_from_msg` returns it; None: no subscription.

        Raises:
            ValueError: on bad arguments.
        """
        if not isinstance(host, str) or not host:
            raise ValueError("host must be a non-empty string")
        if not isinstance(port, int) or not 0 < port < 65536:
            raise ValueError("port must be an integer in 1..65535, got %r" % (port,))
        if on_camera is not None and (not isinstance(camera_topic, str) or not camera_topic.startswith("/")):
            raise ValueError("camera_topic must be an absolute topic name, got %r" % (camera_topic,))
        if not isinstance(camera_throttle_ms, int) or camera_throttle_ms < 0:
            raise ValueError("camera_throttle_ms must be an integer >= 0")
        if heartbeat_hz < 0 or retry_s <= 0 or connect_timeout_s <= 0 or gesture_max_age_s <= 0 or keepalive_s < 0:
            raise ValueError(
                "heartbeat_hz >= 0, retry_s > 0, connect_timeout_s > 0, gesture_max_age_s > 0 and "
                "keepalive_s >= 0 required"
            )
        self.host = host
        self.port = port
        self.heartbeat_hz = float(heartbeat_hz)
        self.retry_s = float(retry_s)
        self.connect_timeout_s = float(connect_timeout_s)
        self.gesture_max_age_s = float(gesture_max_age_s)
        self.keepalive_s = float(keepalive_s)
        self._callbacks = {
            STATUS_TOPIC: on_status,
            STATE_TOPIC: on_state,
            PATH_QUEUE_TOPIC: on_path_queue,
        }
        self._on_connection = on_connection
        self._on_camera = on_camera
        self._on_preflight = on_preflight
        self.camera_topic = camera_topic
        self.camera_throttle_ms = camera_throttle_ms
        self._outbox: queue.Queue = queue.Queue(maxsize=32)
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._connected_evt = threading.Event()
        self._thread = None
        self._lock = threading.Lock()
        self._ros = None
        self._pubs = {}
        self._subs = []
        self._seq = 0
        self.sent_gestures = 0
        self.dropped_gestures = 0
        self.connect_count = 0
        self._alive = None  # the connection's protocol while the keepalive watches it
        self._unanswered = None  # when the first ping not yet answered went out (monotonic; reactor thread)
        self._pings = 0  # pings sent since then (reactor thread)
        self._ping_queued = False  # a ping handed to the reactor and not yet sent
        self._next_ping = 0.0

    # ----------------------------------------------------------------- public API
    @property
    def address(self) -> str:
        """``ws://host:port`` of the bridge."""
        return "ws://%s:%d" % (self.host, self.port)

    @property
    def connected(self) -> bool:
        """True while the WebSocket to the bridge is open."""
        ros = self._ros
        return bool(ros is not None and ros.is_connected and self._connected_evt.is_set())

    def start(self) -> "RobotLink":
        """Start the background thread (connects as soon as the bridge is reachable)."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="rbd-link", daemon=True)
            self._thread.start()
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """Close the connection and stop the background thread."""
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    def send_gesture(self, command: str) -> bool:
        """Queue a trick command for ``/rbd_gestrec/gesture``; never blocks.

        Args:
            command: the trick name (e.g. ``walk``).

        Returns:
            False if it was dropped at once (link down or queue full), True if queued.
        """
        if not isinstance(command, str) or not command:
            raise ValueError("command must be a non-empty string")
        if not self.connected:
            self.dropped_gestures += 1
            LOG.warning("link down: gesture %r not sent", command)
            return False
        try:
            self._outbox.put_nowait((time.monotonic(), command))
        except queue.Full:
            self.dropped_gestures += 1
            return False
        self._wake.set()
        return True

    def request_reconnect(self) -> None:
        """Make the background thread try to connect now instead of after the retry pause."""
        self._force = True
        self._wake.set()

    def wait_connected(self, timeout: float) -> bool:
        """Block up to ``timeout`` seconds until the link is up; return whether it is."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.connected:
                return True
            self._connected_evt.wait(min(0.05, max(0.0, deadline - time.monotonic())))
        return self.connected

    def em_stop(self, engage: bool, timeout: float = 3.0) -> tuple[bool, str]:
        """Call ``/rbd_controller/em_stop`` (SetBool); blocks the caller up to ``timeout``.

        When the link is down it first asks for an immediate reconnection and waits for it
        (still within ``timeout``). When the connection drops before the answer came (a lossy
        WLAN: the keepalive gave it up), the call is made again on the next connection, still
        within ``timeout``: a SetBool is the same request twice. Nothing is sent once the call
        has returned: the request is never queued for later delivery.

        Args:
            engage: True engages the emergency stop, False releases it.
            timeout: total time allowed [s].

        Returns:
            (success, message) — success is True only if the controller answered success.
        """
        from twisted.internet import reactor  # roslibpy's transport on CPython

        deadline = time.monotonic() + timeout
        dropped = 0  # connections lost with the call in flight
        while True:
            if not self.connected:
                self.request_reconnect()
                if not self.wait_connected(max(0.0, deadline - time.monotonic())):
                    lost = " (%d connection(s) lost during the call)" % dropped if dropped else ""
                    return False, "no connection to %s: e-stop NOT delivered%s" % (self.address, lost)
            ros = self._ros
            if ros is None:
                continue
            answer = concurrent.futures.Future()  # the response's values, or the bridge's error
            service = roslibpy.Service(ros, EM_STOP_SERVICE, "std_srvs/SetBool")
            request = roslibpy.ServiceRequest({"data": bool(engage)})

            def failed(error: object, answer: concurrent.futures.Future = answer) -> None:
                answer.set_exception(RuntimeError(error))

            # sent from the reactor thread, where roslibpy keeps its table of pending calls
            reactor.callFromThread(service.call, request, answer.set_result, failed)
            while not answer.done() and time.monotonic() < deadline and self._ros is ros and ros.is_connected:
                concurrent.futures.wait([answer], timeout=0.02)
            if answer.done():
                try:
                    values = answer.result()
                except RuntimeError as exc:
                    return False, "em_stop call failed: %s" % (exc,)
                return bool(values.get("success", False)), str(values.get("message", ""))
            if time.monotonic() >= deadline:
                return False, "em_stop call failed: no answer within %.1f s: e-stop NOT confirmed" % timeout
            dropped += 1  # the connection is gone with the call: again on the next one
            LOG.warning("link lost with an e-stop call in flight: calling again on the next connection")

    def get_tricks(self, timeout: float = 3.0) -> dict:
        """The robot's tricks, read from ``/rbd_navigation/tricks`` through the bridge's rosapi.

        Blocks the caller up to ``timeout`` (call it off the UI thread). The bridge must
        allow reading the parameter (``params_glob`` of rbd_bridge.launch).

        Returns:
            {trick: [names of its steps]} (see :func:`tricks_from_param`).

        Raises:
            ConnectionError: when the link is down or the bridge does not answer in time.
            ValueError: when the bridge refuses or the value is malformed.
        """
        ros = self._ros
        if ros is None or not self.connected:
            raise ConnectionError("no connection to %s" % self.address)
        try:
            value = roslibpy.Param(ros, TRICKS_PARAM).get(timeout=timeout)
        except RosTimeoutError as exc:
            raise ConnectionError("reading %s timed out after %.1f s" % (TRICKS_PARAM, timeout)) from exc
        except Exception as exc:  # ServiceException (refused by the bridge) or a broken connection
            raise ValueError("reading %s failed: %s" % (TRICKS_PARAM, exc)) from exc
        if value is None:
            raise ValueError("%s is not set on the robot (is rbd_navigation running?)" % TRICKS_PARAM)
        return tricks_from_param(value)

    def run_preflight(self, timeout: float = 20.0, duration: float = 0.0) -> dict:
        """Run the robot's preflight now (``/preflight/run``) and return its report.

        The checks only observe the robot's graph (nothing moves). Blocks the caller up to
        ``timeout`` (call it off the UI thread); the robot observes for ``duration`` and then
        probes the hosts' clocks, so allow several seconds more than ``duration``.

        Args:
            timeout: time allowed for the call [s].
            duration: observation length [s] (0: the robot's default, 3 s; at most 10).

        Returns:
            the report (see :func:`preflight_report_from_msg`).

        Raises:
            ConnectionError: when the link is down or the robot does not answer in time.
            ValueError: when the service is missing or refused (no preflight_server on the
                robot, or the bridge does not allow it) or the answer is malformed.
        """
        if not 0.0 <= duration <= PREFLIGHT_MAX_DURATION_S:
            raise ValueError("duration must be within 0..%g s, got %r" % (PREFLIGHT_MAX_DURATION_S, duration))
        ros = self._ros
        if ros is None or not self.connected:
            raise ConnectionError("no connection to %s: preflight not run" % self.address)
        try:
            service = roslibpy.Service(ros, PREFLIGHT_SERVICE, PREFLIGHT_SERVICE_TYPE)
            response = service.call(roslibpy.ServiceRequest({"duration": float(duration)}), timeout=timeout)
        except RosTimeoutError as exc:
            raise ConnectionError("%s did not answer within %.1f s" % (PREFLIGHT_SERVICE, timeout)) from exc
        except Exception as exc:  # ServiceException: missing or refused; or a broken connection
            raise ValueError("%s failed: %s (is rbd_bringup's preflight_server running and the service in the "
                             "bridge's allow-list?)" % (PREFLIGHT_SERVICE, exc)) from exc
        report = response.get("report") if hasattr(response, "get") else None  # a ServiceResponse (UserDict)
        return preflight_report_from_msg(report)

    # ------------------------------------------------------------- worker thread
    _force = False

    def _run(self) -> None:
        next_try = 0.0
        next_beat = 0.0
        was_connected = False
        while not self._stop.is_set():
            now = time.monotonic()
            if not self.connected:
                if was_connected:
                    was_connected = False
                    self._connected_evt.clear()
                    self._teardown()
                    self._notify(False)
                    LOG.warning("link to %s lost; reconnecting", self.address)
                if now >= next_try or self._force:
                    self._force = False
                    if self._try_connect():
                        was_connected = True
                        next_beat = 0.0
                        self._notify(True)
                        continue
                    next_try = time.monotonic() + self.retry_s
                self._drain(send=False)
            else:
                self._keepalive(now)
                self._drain(send=True)
                if self.heartbeat_hz > 0 and now >= next_beat:
                    next_beat = now + 1.0 / self.heartbeat_hz
                    self._heartbeat()
            self._wake.wait(0.05)
            self._wake.clear()
        self._drain(send=self.connected)  # a gesture queued before stop() is sent, not lost
        self._connected_evt.clear()
        self._teardown()

    def _notify(self, up: bool) -> None:
        if self._on_connection is not None:
            try:
                self._on_connection(up)
            except Exception:  # a UI callback must never kill the link thread
                LOG.exception("on_connection callback failed")

    # One roslibpy event-loop manager for every connection of the process: each new manager
    # would start another Twisted log observer, and a link that retries every second for
    # hours would pile them up.
    _shared_manager = None

    def _try_connect(self) -> bool:
        """One connection attempt; an unexpected error counts as a failed attempt.

        The link thread must outlive anything the WebSocket stack raises.
        """
        try:
            return self._connect()
        except Exception:
            LOG.exception("connection attempt to %s failed unexpectedly; retrying", self.address)
            self._teardown()
            return False

    def _connect(self) -> bool:
        ros = roslibpy.Ros(self.host, self.port)
        # Reconnection is ours (a fresh client per attempt): only switch the factory's own retry
        # off. factory.stopTrying() would also stop the connector, which roslibpy has already
        # handed to the reactor thread: from this thread that raced with the reactor (a
        # KeyError in epoll killed the link thread in one test run) or aborted the attempt.
        ros.factory.continueTrying = 0
        if RobotLink._shared_manager is not None and hasattr(ros.factory, "_manager"):
            ros.factory._manager = RobotLink._shared_manager
        else:
            RobotLink._shared_manager = ros.factory.manager
        try:
            ros.run(timeout=self.connect_timeout_s)
        except Exception as exc:
            LOG.debug("cannot connect to %s: %s", self.address, exc)
            self._abandon(ros)
            return False
        with self._lock:
            self._ros = ros
            self._pubs = {
                GESTURE_TOPIC: roslibpy.Topic(ros, GESTURE_TOPIC, "std_msgs/String", reconnect_on_close=False),
                HEARTBEAT_TOPIC: roslibpy.Topic(ros, HEARTBEAT_TOPIC, "std_msgs/Header", reconnect_on_close=False),
            }
            for pub in self._pubs.values():
                pub.advertise()
            self._subs = []
            for name, msg_type in (
                (STATUS_TOPIC, "std_msgs/String"),
                (STATE_TOPIC, "std_msgs/String"),
                (PATH_QUEUE_TOPIC, "rbd_msgs/PathQueue"),
            ):
                if self._callbacks[name] is None:
                    continue
                topic = roslibpy.Topic(ros, name, msg_type, reconnect_on_close=False)
                topic.subscribe(self._make_handler(name))
                self._subs.append(topic)
            if self._on_camera is not None:
                # queue_length 1: a bridge with a slow link sends the newest frame, not a backlog
                topic = roslibpy.Topic(ros, self.camera_topic, CAMERA_TYPE, throttle_rate=self.camera_throttle_ms,
                                       queue_length=1, reconnect_on_close=False)
                topic.subscribe(self._camera_handler)
                self._subs.append(topic)
            if self._on_preflight is not None:
                topic = roslibpy.Topic(ros, PREFLIGHT_TOPIC, PREFLIGHT_TYPE, queue_length=1, reconnect_on_close=False)
                topic.subscribe(self._preflight_handler)
                self._subs.append(topic)
        self._watch(ros)
        self.connect_count += 1
        self._connected_evt.set()
        LOG.info("connected to %s", self.address)
        return True

    # The keepalive: every keepalive_s / 5 the link thread has the reactor send a WebSocket ping;
    # a connection that answers nothing (no pong, no message) for keepalive_s after a ping went out
    # is dropped. autobahn's built-in auto-ping was used before; in about one test-suite run in two
    # its first ping was never scheduled and a silent link stayed "connected". The time is counted
    # from the ping the reactor actually sent, and the verdict is the reactor's, after it has read
    # its socket: a laptop too busy to run this process for a while (the reactor starved) must not
    # take its own stall for the robot's silence. The silence must also span KEEPALIVE_PINGS pings
    # sent one cadence apart (a stalled reactor never has more than one ping queued): a stall of the
    # whole process that ends just before the verdict is due leaves no time for the answer, which
    # the in-process peer of CI's niced tests sent late for the same stall.
    def _watch(self, ros: "roslibpy.Ros") -> None:
        proto = getattr(ros.factory, "_proto", None)
        self._alive = None
        self._unanswered = None
        if self.keepalive_s <= 0 or proto is None or not hasattr(proto, "sendPing"):
            return

        def heard() -> None:  # reactor thread
            self._unanswered = None
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

    def _keepalive(self, now: float) -> None:
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
        self._next_ping = time.monotonic() + self._ping_period()  # the cadence of pings actually sent
        self._pings = 1 if self._unanswered is None else self._pings + 1
        if self._unanswered is None:
            from twisted.internet import reactor

            sent = self._unanswered = time.monotonic()
            reactor.callLater(self.keepalive_s, self._judge, proto, sent, sent + self.keepalive_s)

    def _judge(self, proto: object, sent: float, due: float) -> None:
        """Reactor thread: drop the connection if the ping sent at ``sent`` is still unanswered."""
        if proto is not self._alive or self._unanswered != sent:
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
        self._connected_evt.clear()  # seen as down at once; the link thread tears it down
        proto.dropConnection(True)

    def _make_handler(self, name: str) -> Callable[[dict], None]:
        callback = self._callbacks[name]

        def handle(msg: dict) -> None:
            try:
                if name == PATH_QUEUE_TOPIC:
                    names = msg.get("names") if isinstance(msg, dict) else None
                    if not isinstance(names, list):
                        LOG.warning("malformed path queue ignored: %r", msg)
                        return
                    callback([str(n) for n in names])
                else:
                    data = msg.get("data") if isinstance(msg, dict) else None
                    if not isinstance(data, str):
                        LOG.warning("malformed %s message ignored: %r", name, msg)
                        return
                    callback(data)
            except Exception:
                LOG.exception("callback for %s failed", name)

        return handle

    def _camera_handler(self, msg: dict) -> None:
        try:
            if not isinstance(msg, dict) or not isinstance(msg.get("data"), str):
                LOG.warning("malformed camera message ignored")
                return
            self._on_camera(msg)
        except Exception:
            LOG.exception("camera callback failed")

    def _preflight_handler(self, msg: dict) -> None:
        try:
            report = preflight_report_from_msg(msg)
        except ValueError as exc:
            LOG.warning("malformed preflight report ignored: %s", exc)
            return
        try:
            self._on_preflight(report)
        except Exception:
            LOG.exception("preflight callback failed")

    def _drain(self, send: bool) -> None:
        while True:
            try:
                stamp, command = self._outbox.get_nowait()
            except queue.Empty:
                return
            if not send or time.monotonic() - stamp > self.gesture_max_age_s:
                self.dropped_gestures += 1
                LOG.warning("gesture %r dropped (link down or too old)", command)
                continue
            try:
                self._pubs[GESTURE_TOPIC].publish(roslibpy.Message({"data": command}))
                self.sent_gestures += 1
            except Exception:
                self.dropped_gestures += 1
                LOG.exception("publishing gesture failed")

    def _heartbeat(self) -> None:
        self._seq += 1
        now = time.time()
        msg = {"seq": self._seq, "stamp": {"secs": int(now), "nsecs": int((now % 1) * 1e9)}, "frame_id": "rbd_local"}
        try:
            self._pubs[HEARTBEAT_TOPIC].publish(roslibpy.Message(msg))
        except Exception:
            LOG.exception("heartbeat failed")

    def _teardown(self) -> None:
        self._alive = None
        with self._lock:
            ros, self._ros = self._ros, None
            self._pubs, self._subs = {}, []
        if ros is not None:
            self._close_quietly(ros)

    @staticmethod
    def _abandon(ros: "roslibpy.Ros") -> None:
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

    @staticmethod
    def _close_quietly(ros: "roslibpy.Ros") -> None:
        try:
            ros.factory.stopTrying()
            if ros.is_connected:
                ros.close(timeout=1.0)
        except Exception:
            LOG.debug("closing the old connection failed", exc_info=True)

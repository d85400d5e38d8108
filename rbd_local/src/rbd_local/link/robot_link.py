"""The robot link: :class:`RobotLink`, the laptop app's one connection to the robot's bridge.

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

The names it uses are in :mod:`rbd_local.robot_names`, the messages it unpacks in
:mod:`rbd_local.robot_messages`, one roslibpy client in :mod:`rbd_local.link.connection`, the
keep-alive in :mod:`rbd_local.link.keepalive`, the service calls (e-stop, tricks, preflight) in
:mod:`rbd_local.link.service_calls`.
"""

import logging
import queue
import threading
import time
from typing import Callable

import roslibpy

from rbd_local.link import connection
from rbd_local.link.keepalive import KeepAlive
from rbd_local.link.service_calls import ServiceCalls
from rbd_local.robot_messages import preflight_report_from_msg
from rbd_local.robot_names import (
    CAMERA_TOPIC,
    CAMERA_TYPE,
    GESTURE_TOPIC,
    HEARTBEAT_TOPIC,
    PATH_QUEUE_TOPIC,
    PREFLIGHT_TOPIC,
    PREFLIGHT_TYPE,
    STATE_TOPIC,
    STATUS_TOPIC,
)

LOG = logging.getLogger("rbd_local.link")


class RobotLink(ServiceCalls):
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
        #: pings the connection and drops it when silent (see rbd_local.link.keepalive)
        self.keepalive = KeepAlive(self.keepalive_s, self.address, on_silent=self._connected_evt.clear)

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
                self.keepalive.tick(now)
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
        ros = connection.open_client(self.host, self.port, self.connect_timeout_s)
        if ros is None:
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
        self.keepalive.watch(connection.protocol(ros))
        self.connect_count += 1
        self._connected_evt.set()
        LOG.info("connected to %s", self.address)
        return True

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
        self.keepalive.forget()
        with self._lock:
            ros, self._ros = self._ros, None
            self._pubs, self._subs = {}, []
        if ros is not None:
            connection.close_quietly(ros)

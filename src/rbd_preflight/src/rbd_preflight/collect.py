"""Preflight's collector: watches the running ROS graph and fills a ``preflight.Observation``.

A thin rospy adapter; every decision is in :mod:`rbd_preflight`. It needs an initialised
rospy node (the ``preflight`` command and the ``preflight_server`` node make one). What it does
during one run (``duration`` seconds, 3 by default):

- subscribes the sensor and state topics, keeps receive times (ROS time) and header stamps, the
  last cloud, the last zone state, the last ZED2 covariance, the driver's diagnostics, the latched
  ``/rbd_localization/localized`` and the map correction's mode (its diagnostics);
- listens to /tf and /tf_static itself to know every edge's publisher (a frame with two parents),
  and looks the mounts and the feet up in a tf2 buffer at the end;
- taps LCM_High_State / LCM_High_Cmd on the driver's LCM URL when the ``lcm`` module is there and
  the URL is reachable from this host (the packet sizes on the wire, not the driver's belief);
- meanwhile reads the clock of every other host of the graph (``rbd_preflight.clock_probe``) and
  asks rbd_bridge who is connected.

Everything it subscribes is dropped again at the end, so the full cloud is read only while a
preflight runs.
"""

import base64
import json
import os
import socket
import threading
import time
from typing import Dict, List, Optional, Tuple

import numpy as np
import rosgraph
import rospy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from sensor_msgs.msg import Imu, PointCloud2
from std_msgs.msg import Bool, String
from tf2_msgs.msg import TFMessage

import rbd_preflight as preflight
from rbd_msgs.msg import CollisionState
from rbd_preflight import clock_probe

try:
    import tf2_ros
except ImportError as _exc:  # Melodic + Python 3: its tf2_py is built for Python 2 only
    tf2_ros, TF2_MISSING = None, str(_exc)
TF2_FIX = "build geometry2 from source in the workspace for Python 3 (README: Melodic)"


def require_tf2() -> None:
    """Stop with a FATAL naming the fix when tf2_ros does not import (the mounts are looked up in TF)."""
    if tf2_ros is None:
        rospy.logfatal("preflight: tf2_ros does not import (%s): %s", TF2_MISSING, TF2_FIX)
        raise SystemExit(1)

BRIDGE_NODE = "/rbd_bridge"
#: rbd_localization's map correction: latched, false until localized in a loaded map.
LOCALIZED_TOPIC = "/rbd_localization/localized"
TOPICS = {
    "points": ("/ouster/points", PointCloud2),
    "imu": ("/ouster/imu", Imu),
    "zed2": ("/zed2/zed_node/pose_with_covariance", PoseWithCovarianceStamped),
    "zone": ("/rbd_lidar/state", CollisionState),
    "pose": ("/rbd_localization/pose", PoseStamped),
    "estop": ("/rbd_controller/estop", Bool),
}


def cloud_layout(msg: PointCloud2) -> dict:
    """The layout facts of a PointCloud2 (``preflight.Observation.cloud``)."""
    return {
        "fields": [(f.name, f.offset, f.datatype, f.count) for f in msg.fields],
        "point_step": msg.point_step,
        "row_step": msg.row_step,
        "height": msg.height,
        "width": msg.width,
        "is_bigendian": bool(msg.is_bigendian),
        "data_len": len(msg.data),
        "frame_id": msg.header.frame_id,
    }


def cloud_xyz(msg: PointCloud2) -> Optional[np.ndarray]:
    """x, y, z of every point with a return (N x 3, the cloud's frame), or None if there are no FLOAT32 x y z."""
    fields = {f.name: f for f in msg.fields}
    if msg.is_bigendian or any(n not in fields or fields[n].datatype != 7 for n in ("x", "y", "z")):
        return None
    n = msg.width * msg.height
    if n == 0 or msg.point_step < 12 or len(msg.data) < n * msg.point_step:
        return None
    dtype = np.dtype({"names": ["x", "y", "z"], "formats": ["<f4"] * 3,
                      "offsets": [fields[k].offset for k in ("x", "y", "z")], "itemsize": msg.point_step})
    pts = np.frombuffer(msg.data, dtype=dtype, count=n)
    xyz = np.stack([pts["x"], pts["y"], pts["z"]], axis=1).astype(float)
    keep = np.all(np.isfinite(xyz), axis=1) & np.any(xyz != 0.0, axis=1)
    return xyz[keep]


def lidar_mode(metadata_json: str) -> Optional[str]:
    """``lidar_mode`` of ouster metadata (legacy top level, or ``config_params`` in newer firmware)."""
    try:
        meta = json.loads(metadata_json)
    except ValueError:
        return None
    if not isinstance(meta, dict):
        return None
    mode = meta.get("lidar_mode") or (meta.get("config_params") or {}).get("lidar_mode")
    return str(mode) if mode else None


def websocket_handshake(host: str, port: int, timeout: float = 2.0) -> Optional[str]:
    """None if a WebSocket server on host:port answers the opening handshake with 101, else the error."""
    key = base64.b64encode(os.urandom(16)).decode()
    request = ("GET / HTTP/1.1\r\nHost: %s:%d\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               "Sec-WebSocket-Key: %s\r\nSec-WebSocket-Version: 13\r\n\r\n" % (host, port, key))
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            sock.sendall(request.encode())
            reply = b""
            while b"\r\n" not in reply:
                chunk = sock.recv(1024)
                if not chunk:
                    break
                reply += chunk
            # a close frame (opcode 8, masked, status 1000) so the server ends the session cleanly
            sock.sendall(b"\x88\x82" + b"\x00\x00\x00\x00" + b"\x03\xe8")
    except OSError as exc:
        return str(exc)
    status = reply.split(b"\r\n", 1)[0].decode(errors="replace")
    return None if " 101 " in status + " " else "answered %r" % status


class _Tap:
    """Counts the sizes of the LCM packets on the driver's URL (optional: needs the lcm module)."""

    def __init__(self, url: str) -> None:
        import lcm  # only where the Python LCM binding is installed

        self.url = url
        self.state_sizes = {}  # type: Dict[int, int]
        self.cmd_sizes = {}  # type: Dict[int, int]
        self.lc = lcm.LCM(url)
        self.lc.subscribe("LCM_High_State", lambda _c, data: self._count(self.state_sizes, data))
        self.lc.subscribe("LCM_High_Cmd", lambda _c, data: self._count(self.cmd_sizes, data))
        self.running = True
        self.t0 = time.monotonic()
        self.t1 = None
        self.thread = threading.Thread(target=self._run, name="preflight-lcm", daemon=True)
        self.thread.start()

    @staticmethod
    def _count(table: Dict[int, int], data: bytes) -> None:
        table[len(data)] = table.get(len(data), 0) + 1

    def _run(self) -> None:
        while self.running:
            self.lc.handle_timeout(50)

    def stop(self) -> dict:
        self.running = False
        self.thread.join(1.0)
        self.t1 = time.monotonic()
        return {"state_sizes": dict(self.state_sizes), "cmd_sizes": dict(self.cmd_sizes),
                "span": self.t1 - self.t0, "url": self.url}


class Collector:
    """One preflight observation of the graph this process's rospy node is connected to."""

    def __init__(self, duration: float = 3.0, tap_lcm: bool = True, measure_clocks: bool = True) -> None:
        """Configure one run.

        Args:
            duration: how long to watch [s].
            tap_lcm: also listen on the driver's LCM URL.
            measure_clocks: read the other hosts' clocks.
        """
        self.duration = float(duration)
        self.tap_lcm = tap_lcm
        self.measure_clocks = measure_clocks
        self.lock = threading.Lock()
        self.obs = preflight.Observation()
        self.recv = {k: [] for k in TOPICS}  # type: Dict[str, List[Tuple[float, Optional[float]]]]
        self.last_cloud = None
        self.metadata = None
        self.edges = {}  # (parent, child, publisher) -> static
        self._tap = None
        self._tap_tried = False

    # ----------------------------------------------------------------------- callbacks
    def _stamped(self, key: str) -> "callable":
        def cb(msg: object) -> None:
            now = rospy.get_time()
            header = getattr(msg, "header", None)
            stamp = header.stamp.to_sec() if header is not None else None
            with self.lock:
                self.recv[key].append((now, stamp))
                if key == "points":
                    self.last_cloud = msg
                elif key == "zone":
                    self.obs.zone_last = {"stale": msg.stale, "error": msg.error, "collision": msg.collision,
                                          "points": list(msg.points)}
                elif key == "zed2":
                    self.obs.zed2_covariance = list(msg.pose.covariance)
        return cb

    def _on_localized(self, msg: Bool) -> None:
        with self.lock:
            self.obs.localized = bool(msg.data)

    def _on_diag(self, msg: DiagnosticArray) -> None:
        for st in msg.status:
            if st.name == preflight.MAP_CORRECTION_DIAG or st.name.endswith(": " + preflight.MAP_CORRECTION_DIAG):
                mode = {kv.key: kv.value for kv in st.values}.get("mode")
                if mode is not None:
                    with self.lock:
                        self.obs.map_mode = mode
            if st.name == preflight.A1_DIAG_NAME:
                with self.lock:
                    self.obs.a1_diag.append({"level": st.level, "message": st.message,
                                             "values": {kv.key: kv.value for kv in st.values}})
                    if self.tap_lcm and self._tap is None and not self._tap_tried:
                        self._start_tap({kv.key: kv.value for kv in st.values}.get("lcm_url"))

    def _on_tf(self, static: bool) -> "callable":
        def cb(msg: TFMessage) -> None:
            publisher = msg._connection_header.get("callerid", "?") if hasattr(msg, "_connection_header") else "?"
            with self.lock:
                for t in msg.transforms:
                    self.edges[(t.header.frame_id, t.child_frame_id, publisher)] = static
        return cb

    def _on_metadata(self, msg: String) -> None:
        self.metadata = msg.data

    def _start_tap(self, url: Optional[str]) -> None:
        self._tap_tried = True
        if not url:
            return
        try:
            self._tap = _Tap(url)
        except Exception as exc:  # no lcm module, or the URL is not reachable from here
            rospy.logdebug("preflight: no LCM tap on %s: %s", url, exc)

    # ------------------------------------------------------------------------ the run
    def run(self) -> preflight.Observation:
        """Watch for ``duration`` seconds and return the observation."""
        obs = self.obs
        obs.duration = self.duration
        require_tf2()
        if self.tap_lcm:
            for name in ("/rbd_a1_driver/lcm_url", "/rbd_sim/lcm_url"):
                if rospy.has_param(name):
                    self._start_tap(str(rospy.get_param(name)))
                    break
        buffer = tf2_ros.Buffer(cache_time=rospy.Duration(30.0))
        listener = tf2_ros.TransformListener(buffer)
        subs = [rospy.Subscriber(topic, cls, self._stamped(key), queue_size=(2 if key == "points" else 50),
                                 buff_size=(1 << 25 if key == "points" else 65536))
                for key, (topic, cls) in TOPICS.items()]
        subs += [rospy.Subscriber("/diagnostics", DiagnosticArray, self._on_diag, queue_size=50),
                 rospy.Subscriber(LOCALIZED_TOPIC, Bool, self._on_localized, queue_size=5),
                 rospy.Subscriber("/tf", TFMessage, self._on_tf(False), queue_size=200),
                 rospy.Subscriber("/tf_static", TFMessage, self._on_tf(True), queue_size=50),
                 rospy.Subscriber("/ouster/metadata", String, self._on_metadata, queue_size=1)]
        side = []  # bridge and clocks, concurrently with the watching
        side.append(threading.Thread(target=self._bridge, name="preflight-bridge", daemon=True))
        if self.measure_clocks:
            side.append(threading.Thread(target=self._clocks, name="preflight-clocks", daemon=True))
        for t in side:
            t.start()
        t_end = time.monotonic() + self.duration
        while time.monotonic() < t_end and not rospy.is_shutdown():
            time.sleep(0.05)
        obs.now = rospy.get_time()  # the end of the window (unregistering may take a while)
        for sub in subs:
            sub.unregister()
        if self._tap is not None:
            obs.wire = self._tap.stop()
        for t in side:
            t.join(10.0)
        with self.lock:
            for key, samples in self.recv.items():
                obs.streams[key] = preflight.Stream([r for r, _ in samples], [s for _, s in samples])
            if self.last_cloud is not None:
                obs.cloud = cloud_layout(self.last_cloud)
                obs.cloud_xyz = cloud_xyz(self.last_cloud)
            obs.tf_edges = [(p, c, pub, st) for (p, c, pub), st in self.edges.items()]
        if self.metadata:
            obs.lidar_mode = lidar_mode(self.metadata)
        for frame in (obs.lidar_frame, obs.zed2_frame, "collision_zone") + preflight.FEET:
            try:
                t = buffer.lookup_transform(obs.base_frame, frame, rospy.Time(0), rospy.Duration(0.2)).transform
                obs.frames[frame] = ((t.translation.x, t.translation.y, t.translation.z),
                                     (t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w))
            except tf2_ros.TransformException as exc:
                obs.frames[frame] = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        listener.unregister()
        mounts = rospy.get_param("/robodog/mounts", None)
        obs.mounts_file = str(mounts) if mounts else None
        return obs

    def _bridge(self) -> None:
        info = {"node": None}
        try:
            master = rosgraph.Master(rospy.get_name())
            uri = master.lookupNode(BRIDGE_NODE)
            info["node"] = BRIDGE_NODE
            address = str(rospy.get_param(BRIDGE_NODE + "/address", "0.0.0.0") or "0.0.0.0")
            host = clock_probe.host_of(uri) if address in ("0.0.0.0", "::", "") else address
            port = int(rospy.get_param(BRIDGE_NODE + "/actual_port", rospy.get_param(BRIDGE_NODE + "/port", 9090)))
            info.update(host=host, port=port)
            # who is connected, asked before this check's own handshake connects as a client
            try:
                stats = json.loads(self._call_stats())
                info["client_count"] = stats.get("clients")
                info["clients"] = stats.get("client_addresses")
            except Exception as exc:  # an older bridge: count only
                rospy.logdebug("preflight: bridge stats: %s", exc)
            error = websocket_handshake(host, port)
            if error is not None and "timed out" in error:  # a busy robot: one more, longer try
                error = websocket_handshake(host, port, timeout=5.0)
            info.update(listening=error is None, error=error)
        except (OSError, rosgraph.MasterError, ValueError) as exc:
            info["error"] = str(exc)
        with self.lock:
            self.obs.bridge = info

    @staticmethod
    def _call_stats() -> str:
        from std_srvs.srv import Trigger

        rospy.wait_for_service(BRIDGE_NODE + "/stats", timeout=2.0)
        return rospy.ServiceProxy(BRIDGE_NODE + "/stats", Trigger)().message

    def _clocks(self) -> None:
        try:
            clocks = measure_graph_clocks(rospy.get_name())
        except Exception as exc:  # the master went away: leave it unmeasured
            rospy.logwarn("preflight: clocks not measured: %s", exc)
            clocks = None
        with self.lock:
            self.obs.clocks = clocks


def _address(host: str) -> str:
    try:
        return socket.gethostbyname(host)
    except OSError:
        return host


def graph_hosts(me: str) -> Dict[str, List[str]]:
    """Host address -> XML-RPC URLs on it whose servers may send a Date header, best first.

    Hosts are those of the graph's nodes (``me`` excluded); per host: its roslaunch servers, the
    master if it runs there, then the nodes themselves.
    """
    master = rosgraph.Master(me)
    pubs, subs, srvs = master.getSystemState()
    nodes = {n for _t, names in list(pubs) + list(subs) + list(srvs) for n in names} - {me}
    node_uris = []
    for name in sorted(nodes):
        try:
            node_uris.append(master.lookupNode(name))
        except rosgraph.MasterError:
            continue  # gone meanwhile
    hosts = {}  # type: Dict[str, List[str]]
    for uri in node_uris:
        hosts.setdefault(_address(clock_probe.host_of(uri)), [])
    launch_uris = []
    try:
        uris = master.getParam("/roslaunch/uris")
        launch_uris = [u for u in uris.values() if isinstance(u, str)] if isinstance(uris, dict) else []
    except rosgraph.MasterError:
        pass
    for uri in launch_uris + [master.getUri()] + node_uris:
        addr = _address(clock_probe.host_of(uri))
        if addr in hosts and uri not in hosts[addr]:
            hosts[addr].append(uri)
    return hosts


def measure_graph_clocks(me: str, budget: float = 3.0) -> Dict[str, object]:
    """Host -> (offset [s], uncertainty [s], url) or an error text, for every host of the graph.

    One host: nothing is measured (its offset is 0 by definition). Hosts are measured in parallel.
    """
    hosts = graph_hosts(me)
    if len(hosts) <= 1:
        return {h: (0.0, 0.0, "this graph's only host") for h in hosts}
    out = {}  # type: Dict[str, object]

    def one(host: str, urls: List[str]) -> None:
        try:
            out[host] = clock_probe.measure_host(urls[:6], budget=budget)
        except clock_probe.NoDateHeaderError as exc:
            out[host] = str(exc)

    threads = [threading.Thread(target=one, args=kv, daemon=True) for kv in hosts.items()]
    for t in threads:
        t.start()
    for t in threads:
        t.join(budget * 3 + 5)
    for h in hosts:
        out.setdefault(h, "no answer in time")
    return out


def run(duration: float = 3.0, limits: Optional[preflight.Limits] = None, tap_lcm: bool = True,
        measure_clocks: bool = True) -> Tuple[List[preflight.Row], preflight.Observation]:
    """Observe the graph for ``duration`` seconds and evaluate it: (rows, observation)."""
    obs = Collector(duration, tap_lcm=tap_lcm, measure_clocks=measure_clocks).run()
    return preflight.evaluate(obs, limits), obs


def report_message(rows: List[preflight.Row], obs: preflight.Observation) -> "object":
    """The rbd_msgs/PreflightReport of a run."""
    from rbd_msgs.msg import PreflightCheck, PreflightReport

    msg = PreflightReport()
    msg.header.stamp = rospy.Time.from_sec(obs.now) if obs.now else rospy.Time.now()
    msg.ready = preflight.passed(rows)
    msg.duration = obs.duration
    msg.checks = [PreflightCheck(key=r.key, name=r.name, status=r.status, value=r.value, hint=r.hint) for r in rows]
    msg.mounts = ["%s: %s" % kv for kv in preflight.mounts_in_use(obs)]
    msg.mounts_file = obs.mounts_file or ""
    return msg

"""Preflight: is the real robot ready? The checks, free of ROS (issue 16).

The collector (``rbd_bringup.preflight_collect``, a thin rospy adapter) watches the running graph for
a few seconds and fills an :class:`Observation` with what it saw: receive times and header stamps
per topic, the last cloud's layout and points, the A1 driver's diagnostics, transforms, the TF
edges with their publishers, the bridge, the clocks of the hosts. :func:`evaluate` turns that into
one :class:`Row` per check: PASS or FAIL with the measured value and, on FAIL, what to do. A check
whose inputs another check already found missing says SKIP and names that check, so one fault
gives one FAIL line (the cause), not a cascade. The command exits 0 only if every row passes.

The facts checked against come from outside this code base: the ouster-ros point layout, the A1
SDK packet sizes and the drivers' rates as ``../shared/INTERFACES.md`` lists them (written here as
literal tables, not imported from rbd_lidar or rbd_a1_driver).
"""

import math
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

PASS, FAIL, SKIP = "PASS", "FAIL", "SKIP"

#: ouster-ros ``point_type:=original`` (INTERFACES.md §1, master ``include/ouster_ros/os_point.h``):
#: field -> (offset [B], PointField datatype). ring is UINT16 (4) since v0.7.1, UINT8 (2) before.
OUSTER_POINT = {
    "x": (0, (7,)),
    "y": (4, (7,)),
    "z": (8, (7,)),
    "intensity": (16, (7,)),
    "t": (20, (6,)),
    "reflectivity": (24, (4,)),
    "ring": (26, (4, 2)),
    "ambient": (28, (4,)),
    "range": (32, (6,)),
}
OUSTER_POINT_STEP = 48
OS1_ROWS = 32
#: columns_per_frame of the OS1 modes (512x10 ... 4096x5).
OS1_WIDTHS = (512, 1024, 2048, 4096)
DATATYPE_NAMES = {1: "INT8", 2: "UINT8", 3: "INT16", 4: "UINT16", 5: "INT32", 6: "UINT32", 7: "FLOAT32", 8: "FLOAT64"}
#: Unitree SDK HighState sizes on LCM_High_State (INTERFACES.md §2) -> SDK release.
A1_STATE_SIZES = {265: "SDK v3.3/v3.3.1", 1025: "SDK 3.3.3/3.3.4"}
#: Sizes of other releases, for the message (v3.2: 256 B, v3.3.2: 319 B).
A1_OTHER_STATE_SIZES = {256: "SDK v3.2", 319: "SDK v3.3.2"}
A1_HIGH_CMD_SIZE = 113
#: The driver's diagnostics status preflight reads (rbd_a1_driver README, "the diagnostics contract").
A1_DIAG_NAME = "rbd_a1_driver: A1 link"
#: The A1's foot spheres (a1_description): the floor is one radius below a foot frame.
FOOT_RADIUS = 0.02
FEET = ("FR_foot", "FL_foot", "RR_foot", "RL_foot")
#: The A1's nominal standing height (SDK default bodyHeight 0.28 m): the floor without foot frames.
NOMINAL_BODY_HEIGHT = 0.28


class Limits:
    """Thresholds of the checks; every one can be overridden by keyword.

    Rates are minimum rates [Hz], ages and lags [s] (lag = receive time - header stamp; negative
    means a stamp in the future).
    """

    DEFAULTS = {
        "a1_state_min_rate": 100.0,  # SDK LCM server: 500 Hz; mock A1: 250 Hz
        "a1_cmd_min_rate": 100.0,  # driver ~send_rate 250 Hz
        "estop_min_rate": 8.0,  # rbd_controller republishes the flag at 10 Hz
        "lidar_rate_fraction": 0.8,  # of the mode's rate (10 or 20 Hz)
        "lidar_default_hz": 10.0,  # when /ouster/metadata does not say
        "lidar_max_periods": 3.0,  # DESIGN §5: no cloud for 3 scan periods = stale
        "lidar_max_lag": 0.5,
        "imu_min_rate": 80.0,  # ouster IMU 100 Hz
        "imu_max_lag": 0.2,
        "zed2_min_rate": 10.0,  # zed-ros-wrapper v3.8 grab rate 15 Hz
        "zed2_max_lag": 0.5,
        "zed2_max_position_var": 1.0,  # [m^2]
        "zed2_max_orientation_var": 0.25,  # [rad^2]
        "zone_max_age": 0.5,
        "pose_min_rate": 10.0,  # DESIGN §4: pose at >= 10 Hz
        "pose_max_age": 0.5,  # DESIGN §5: no pose for 0.5 s = stale
        "max_future": 0.05,  # a stamp this far ahead of the receive time: a clock problem
        "floor_tolerance": 0.03,  # [m]; mounts are measured to +-2 cm (README "Mounts")
        "floor_max_tilt_deg": 3.0,
        "floor_min_points": 200,
        "clock_max_skew": 0.05,  # [s] between any two ROS hosts
    }

    def __init__(self, **overrides: float) -> None:
        """Defaults, with ``overrides`` by name.

        Raises:
            ValueError: on an unknown name.
        """
        unknown = sorted(set(overrides) - set(self.DEFAULTS))
        if unknown:
            raise ValueError("unknown preflight limit(s): %s" % ", ".join(unknown))
        for key, value in self.DEFAULTS.items():
            setattr(self, key, float(overrides.get(key, value)))


class Stream:
    """Receive times and header stamps of one topic during the observation [s, wall/ROS time]."""

    def __init__(self, recv: Sequence[float] = (), stamps: Sequence[Optional[float]] = ()) -> None:
        """Both lists in arrival order; a stamp is None for messages without a header."""
        self.recv = list(recv)
        self.stamps = list(stamps) if stamps else [None] * len(self.recv)

    @property
    def count(self) -> int:
        """Messages received."""
        return len(self.recv)

    def rate(self) -> float:
        """Messages per second between the first and the last one (0 with fewer than two)."""
        if len(self.recv) < 2 or self.recv[-1] <= self.recv[0]:
            return 0.0
        return (len(self.recv) - 1) / (self.recv[-1] - self.recv[0])

    def age(self, now: float) -> float:
        """Seconds since the last message (inf if none)."""
        return max(0.0, now - self.recv[-1]) if self.recv else float("inf")

    def lags(self) -> List[float]:
        """Receive time minus header stamp of every stamped message."""
        return [r - s for r, s in zip(self.recv, self.stamps) if s is not None]


class Observation:
    """Everything the collector saw; every field may stay empty (the check then says what is missing).

    Attributes:
        duration: length of the observation [s].
        now: time at its end (same clock as the receive times) [s].
        streams: topic key (``points``, ``imu``, ``zed2``, ``zone``, ``pose``, ``estop``) -> Stream.
        cloud: layout of the last ``/ouster/points``: dict with ``fields`` [(name, offset, datatype,
            count)], ``point_step``, ``row_step``, ``height``, ``width``, ``is_bigendian``,
            ``data_len``, ``frame_id``.
        cloud_xyz: (N, 3) points of that cloud in its own frame (NaN/zero returns removed), or None.
        lidar_mode: ``lidar_mode`` of ``/ouster/metadata`` (e.g. ``1024x10``), if seen.
        zone_last: the last ``/rbd_lidar/state`` as a dict (``stale``, ``error``, ``collision``,
            ``points``), if any.
        zed2_covariance: the last ZED2 pose covariance (36 numbers), if any.
        a1_diag: the driver's diagnostics statuses in order, each {``level``, ``message``,
            ``values``: {key: value}}.
        wire: what an LCM tap saw, if one ran: {``state_sizes``: {size: count}, ``cmd_sizes``:
            {size: count}, ``span``: seconds listened, ``url``}.
        base_frame: the robot's body frame (``base_link``).
        frames: frame -> ((x, y, z), (qx, qy, qz, qw)) of base_frame -> frame, or an error text.
        tf_edges: (parent, child, publisher, static) of every transform seen on /tf and /tf_static.
        bridge: {``node``, ``host``, ``port``, ``listening``, ``error``, ``clients``: [peer] or None,
            ``client_count``}; None if the collector did not look.
        clocks: host -> (offset [s], uncertainty [s], source) or an error text; None if not measured.
        mounts_file: the calibration file the robot model was made from, if known.
    """

    def __init__(self) -> None:
        """An empty observation."""
        self.duration = 0.0
        self.now = 0.0
        self.streams = {}  # type: Dict[str, Stream]
        self.cloud = None  # type: Optional[dict]
        self.cloud_xyz = None
        self.lidar_mode = None  # type: Optional[str]
        self.zone_last = None  # type: Optional[dict]
        self.zed2_covariance = None  # type: Optional[Sequence[float]]
        self.a1_diag = []  # type: List[dict]
        self.wire = None  # type: Optional[dict]
        self.base_frame = "base_link"
        self.lidar_frame = "os_sensor"
        self.zed2_frame = "zed2_camera_center"
        self.frames = {}  # type: Dict[str, object]
        self.tf_edges = []  # type: List[Tuple[str, str, str, bool]]
        self.bridge = None  # type: Optional[dict]
        self.clocks = None  # type: Optional[dict]
        self.mounts_file = None  # type: Optional[str]

    def stream(self, key: str) -> Stream:
        """The stream of ``key`` (empty if nothing arrived)."""
        return self.streams.get(key) or Stream()


class Row:
    """One line of the preflight table."""

    __slots__ = ("key", "name", "status", "value", "hint")

    def __init__(self, key: str, name: str, status: str, value: str, hint: str = "") -> None:
        """A check's result: ``status`` PASS/FAIL/SKIP, the measured ``value``, ``hint`` = what to do."""
        self.key, self.name, self.status, self.value, self.hint = key, name, status, value, hint

    def to_dict(self) -> dict:
        """As a plain dict (JSON, the ROS message)."""
        return {k: getattr(self, k) for k in self.__slots__}

    def __repr__(self) -> str:
        """``Row(key, status, value)``."""
        return "Row(%r, %r, %r)" % (self.key, self.status, self.value)


# ------------------------------------------------------------------------------------ helpers


def _fmt_rate(stream: Stream) -> str:
    if stream.count == 0:
        return "nothing received"
    if stream.count == 1:
        return "1 message"
    return "%.1f Hz" % stream.rate()


def _lag_problem(stream: Stream, max_lag: float, max_future: float) -> Optional[str]:
    """A text if the header stamps are not in this host's ROS time (too old or in the future)."""
    lags = stream.lags()
    if not lags:
        return None
    lag = float(np.median(lags))
    if lag < -max_future:
        return "stamps %.3f s in the future" % -lag
    if lag > max_lag:
        return "stamps %.3f s old on arrival" % lag
    return None


def _rate_check(obs: Observation, key: str, topic: str, min_rate: float, max_age: float, max_lag: float,
                max_future: float, hint_silent: str, hint_slow: str, hint_stamps: str) -> Tuple[str, str, str]:
    """(status, value, hint) of a stream that must arrive at >= min_rate, fresh, stamped in ROS time."""
    s = obs.stream(key)
    if s.count == 0:
        return FAIL, "%s: nothing in %.1f s" % (topic, obs.duration), hint_silent
    rate = s.rate()
    age = s.age(obs.now)
    value = "%s, last %.2f s ago" % (_fmt_rate(s), age)
    if rate < min_rate:
        return FAIL, value + " (need >= %.0f Hz)" % min_rate, hint_slow
    if age > max_age:
        return FAIL, value + " (stale after %.2f s)" % max_age, hint_silent
    problem = _lag_problem(s, max_lag, max_future)
    if problem:
        return FAIL, value + ", " + problem, hint_stamps
    return PASS, value, ""


def _last_diag(obs: Observation) -> Optional[dict]:
    return obs.a1_diag[-1] if obs.a1_diag else None


def _diag_float(diag: dict, key: str) -> Optional[float]:
    try:
        return float(diag["values"][key])
    except (KeyError, TypeError, ValueError):
        return None


def size_name(size: int) -> str:
    """``1025 B (SDK 3.3.3/3.3.4)``, ``300 B (unknown)``."""
    if size in A1_STATE_SIZES:
        return "%d B (%s)" % (size, A1_STATE_SIZES[size])
    if size in A1_OTHER_STATE_SIZES:
        return "%d B (%s, not supported)" % (size, A1_OTHER_STATE_SIZES[size])
    return "%d B (unknown)" % size


def quaternion_to_rpy(q: Sequence[float]) -> Tuple[float, float, float]:
    """Roll, pitch, yaw [rad] of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


def quaternion_matrix(q: Sequence[float]) -> np.ndarray:
    """3x3 rotation of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def format_mount(transform: object) -> str:
    """``xyz (-0.080, 0.000, 0.070) m, rpy (0.0, 0.0, 0.0) deg``."""
    (x, y, z), q = transform
    r, p, yw = (math.degrees(a) for a in quaternion_to_rpy(q))
    return "xyz (%.3f, %.3f, %.3f) m, rpy (%.1f, %.1f, %.1f) deg" % (x, y, z, r, p, yw)


# ------------------------------------------------------------------------------ the floor


def fit_plane(points: np.ndarray, threshold: float = 0.03, iterations: int = 150,
              seed: int = 0) -> Optional[Tuple[np.ndarray, float, int]]:
    """Dominant plane of ``points`` (N x 3): RANSAC, then a least-squares refit on its inliers.

    Returns:
        (unit normal with z >= 0, d, inlier count) for the plane ``n . p + d = 0``, or None with
        fewer than 3 points.
    """
    pts = np.asarray(points, dtype=float)
    if pts.shape[0] < 3:
        return None
    rng = np.random.RandomState(seed)
    best, best_count = None, -1
    for _ in range(iterations):
        a, b, c = pts[rng.choice(pts.shape[0], 3, replace=False)]
        n = np.cross(b - a, c - a)
        norm = np.linalg.norm(n)
        if norm < 1e-9:
            continue
        n = n / norm
        count = int(np.count_nonzero(np.abs(pts.dot(n) - n.dot(a)) < threshold))
        if count > best_count:
            best, best_count = (n, -n.dot(a)), count
    if best is None:
        return None
    n, d = best
    inliers = pts[np.abs(pts.dot(n) + d) < threshold]
    centre = inliers.mean(axis=0)
    # the smallest singular vector of the centred inliers is the refitted normal
    n = np.linalg.svd(inliers - centre, full_matrices=False)[2][-1]
    if n[2] < 0:
        n = -n
    d = -float(n.dot(centre))
    return n, d, int(np.count_nonzero(np.abs(pts.dot(n) + d) < threshold))


def floor_check(points_base: np.ndarray, contacts: Optional[np.ndarray], limits: Limits,
                nominal_height: float = NOMINAL_BODY_HEIGHT) -> Tuple[str, str, str, dict]:
    """The floor the LiDAR sees against where the feet (or the nominal body height) put it.

    Args:
        points_base: the cloud in the body frame (N x 3) [m].
        contacts: the feet's floor contact points in the body frame (K x 3), or None: then the
            floor is expected level at ``-nominal_height``.
        limits: ``floor_tolerance``, ``floor_max_tilt_deg``, ``floor_min_points``.
        nominal_height: body height without foot frames [m].

    Returns:
        (status, value, hint, numbers): numbers has ``offset`` (how far the LiDAR's floor lies
        above the expected one [m]; a mount z too high by d gives +d), ``tilt_deg`` and ``inliers``.
    """
    pts = np.asarray(points_base, dtype=float).reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if contacts is not None and len(contacts) >= 3:
        c = np.asarray(contacts, dtype=float)
        centre = c.mean(axis=0)
        n_exp = np.linalg.svd(c - centre, full_matrices=False)[2][-1]
        if n_exp[2] < 0:
            n_exp = -n_exp
        d_exp = -float(n_exp.dot(centre))
        source = "feet"
    else:
        n_exp, d_exp, source = np.array([0.0, 0.0, 1.0]), nominal_height, "nominal %.2f m" % nominal_height
    # candidates: 0.5-5 m around the body, within 0.3 m of the expected floor
    horizontal = np.hypot(pts[:, 0], pts[:, 1])
    near = np.abs(pts.dot(n_exp) + d_exp) < 0.3
    cand = pts[near & (horizontal > 0.5) & (horizontal < 5.0)]
    if cand.shape[0] > 6000:
        cand = cand[np.random.RandomState(1).choice(cand.shape[0], 6000, replace=False)]
    numbers = {"offset": None, "tilt_deg": None, "inliers": 0, "expected": source}
    fit = fit_plane(cand) if cand.shape[0] >= 3 else None
    if fit is None or fit[2] < limits.floor_min_points:
        return (FAIL, "no floor in the cloud (%d candidate points within 0.3 m of the expected floor, %s)"
                % (cand.shape[0], source),
                "the LiDAR must see the floor around the robot (standing on a level floor, no cover); "
                "or the os_sensor mount is off by more than 0.3 m", numbers)
    n, d, inliers = fit
    # height of the expected floor's points above the LiDAR's floor, the other way round
    ref = np.asarray(contacts, dtype=float) if source == "feet" else np.array([[0.0, 0.0, -nominal_height]])
    offset = float(-np.mean(ref.dot(n) + d))
    tilt = math.degrees(math.acos(max(-1.0, min(1.0, float(n.dot(n_exp))))))
    numbers.update(offset=offset, tilt_deg=tilt, inliers=inliers)
    value = "floor %+.3f m from the expected one (%s), tilt %.1f deg, %d points" % (offset, source, tilt, inliers)
    if abs(offset) > limits.floor_tolerance:
        where = "high" if offset > 0 else "low"
        return (FAIL, value,
                "the LiDAR's floor is %.0f mm too %s: the os_sensor z in the mounts file is %.0f mm too %s "
                "(or the body height is off); measure the mount again (rbd_bringup README, Mounts)"
                % (abs(offset) * 1000, where, abs(offset) * 1000, where), numbers)
    if tilt > limits.floor_max_tilt_deg:
        return (FAIL, value, "the LiDAR's floor is tilted: check the os_sensor roll/pitch in the mounts file", numbers)
    return PASS, value, "", numbers


# ------------------------------------------------------------------------------ the checks


def check_a1_state(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """HighState arriving at the driver, at the SDK's rate."""
    diag = _last_diag(obs)
    if diag is None:
        return (FAIL, "no '%s' diagnostics in %.1f s" % (A1_DIAG_NAME, obs.duration),
                "start the robot stack (roslaunch rbd_bringup robot.launch): rbd_a1_driver is not running")
    rate = _diag_float(diag, "high_state_rate") or 0.0
    value = "%.0f Hz at the driver" % rate
    if obs.wire is not None:
        span = max(obs.wire.get("span", 0.0), 1e-3)
        known = sum(n for size, n in obs.wire["state_sizes"].items() if size in A1_STATE_SIZES)
        value += ", %.0f Hz on the wire (%s)" % (known / span, obs.wire.get("url", "LCM"))
    if rate < lim.a1_state_min_rate:
        return (FAIL, value + " (need >= %.0f Hz)" % lim.a1_state_min_rate,
                "no usable HighState: is the SDK's lcm_server_high running on the driver's LCM URL (%s)? "
                "is the A1 on and reachable (192.168.123.161)?" % diag["values"].get("lcm_url", "?"))
    return PASS, value, ""


def check_a1_layout(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """The SDK layout the driver detected; no packets of an unknown size."""
    diag = _last_diag(obs)
    if diag is None and obs.wire is None:
        return SKIP, "no driver diagnostics, no LCM tap", ""
    seen = {}  # size -> count of HighStates of an unknown size
    if obs.wire is not None:
        seen = {s: n for s, n in obs.wire["state_sizes"].items() if s not in A1_STATE_SIZES}
    dropped = 0
    if len(obs.a1_diag) >= 2:
        counts = [_diag_float(d, "unknown_size_packets") or 0.0 for d in obs.a1_diag]
        dropped = int(counts[-1] - counts[0])
    layout = diag["values"].get("sdk_layout", "unknown") if diag else "unknown"
    source = diag["values"].get("sdk_layout_source", "?") if diag else "?"
    size = int(_diag_float(diag, "high_state_size") or 0) if diag else 0
    if seen or dropped > 0:
        sizes = ", ".join("%s x%d" % (size_name(s), n) for s, n in sorted(seen.items())) if seen else (
            "%d dropped by the driver, last size %s" % (dropped, size_name(size)))
        return (FAIL, "HighState of an unknown size: %s; driver layout %s" % (sizes, layout),
                "known: 265 B (SDK v3.3/v3.3.1), 1025 B (SDK 3.3.3/3.3.4): build lcm_server_high from one of "
                "them, and run only one LCM server on this URL")
    if layout not in ("3.3", "3.3.4"):
        return (FAIL, "no layout detected (last HighState %s)" % (size_name(size) if size else "none"),
                "no usable HighState yet: see the A1 HighState line")
    expected_size = {"3.3": 265, "3.3.4": 1025}[layout]
    how = "forced" if source == "forced" else "by size"
    return PASS, "SDK %s, HighState %d B (%s)" % (layout, expected_size, how), ""


def check_a1_cmd(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """HighCmd going out at the driver's send rate."""
    diag = _last_diag(obs)
    if diag is None:
        return SKIP, "no driver diagnostics (see A1 HighState)", ""
    rate = _diag_float(diag, "high_cmd_rate") or 0.0
    value = "%.0f Hz sent" % rate
    if obs.wire is not None:
        span = max(obs.wire.get("span", 0.0), 1e-3)
        cmds = obs.wire["cmd_sizes"]
        value += ", %.0f Hz of %d B on the wire" % (cmds.get(A1_HIGH_CMD_SIZE, 0) / span, A1_HIGH_CMD_SIZE)
        odd = {s: n for s, n in cmds.items() if s != A1_HIGH_CMD_SIZE}
        if odd:
            return (FAIL, value + "; also HighCmd of %s" % ", ".join("%d B x%d" % kv for kv in sorted(odd.items())),
                    "another program sends on LCM_High_Cmd: stop it (the A1 takes every command)")
    if rate < lim.a1_cmd_min_rate:
        return (FAIL, value + " (need >= %.0f Hz)" % lim.a1_cmd_min_rate,
                "rbd_a1_driver is not sending: see its log (rosnode info /rbd_a1_driver); lcm_server_high "
                "exits after 20 ms without a command")
    return PASS, value, ""


def check_estop(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """rbd_controller's e-stop signal at 10 Hz, the driver's watchdog armed."""
    s = obs.stream("estop")
    diag = _last_diag(obs)
    armed = diag is not None and diag["values"].get("estop_gate_armed") == "true"
    value = "signal %s, driver gate %s" % (_fmt_rate(s), "armed" if armed else "NOT armed")
    if s.count == 0 or s.rate() < lim.estop_min_rate:
        return (FAIL, value + " (need >= %.0f Hz)" % lim.estop_min_rate,
                "rbd_controller is not republishing /rbd_controller/estop: is it running?")
    if diag is None:
        return FAIL, value + " (no driver diagnostics)", "rbd_a1_driver is not running"
    if not armed:
        return (FAIL, value, "the driver has not armed its e-stop watchdog: ~estop_timeout must be > 0 and "
                "the driver must receive /rbd_controller/estop")
    return PASS, value, ""


def check_lidar_cloud(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """/ouster/points arriving at the mode's rate, fresh, in ROS time."""
    hz = lim.lidar_default_hz
    if obs.lidar_mode and "x" in obs.lidar_mode:
        try:
            hz = float(obs.lidar_mode.split("x")[1])
        except ValueError:
            pass
    status, value, hint = _rate_check(
        obs, "points", "/ouster/points", lim.lidar_rate_fraction * hz, lim.lidar_max_periods / hz, lim.lidar_max_lag,
        lim.max_future,
        "no cloud: is ouster-ros running (ouster_ns:=ouster, proc_mask with PCL) and the OS1 reachable?",
        "cloud slower than the %s mode: the Jetson or the OS1's link is overloaded" % (obs.lidar_mode or "10 Hz"),
        "cloud stamps are not ROS time: ouster-ros timestamp_mode:=TIME_FROM_ROS_TIME (or sync the clocks)")
    if obs.lidar_mode:
        value += " (mode %s)" % obs.lidar_mode
    return status, value, hint


def check_lidar_layout(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """The last cloud has ouster-ros' 48-byte point, 32 rows, organised, little-endian, in os_sensor."""
    c = obs.cloud
    if c is None:
        return SKIP, "no cloud to check (see /ouster/points)", ""
    fields = {f[0]: f for f in c["fields"]}
    problems = []
    for name, (offset, types) in sorted(OUSTER_POINT.items(), key=lambda kv: kv[1][0]):
        f = fields.get(name)
        if f is None:
            problems.append("no field %s" % name)
        elif f[1] != offset or f[2] not in types or f[3] != 1:
            problems.append("%s %s@%d (need %s@%d)" % (name, DATATYPE_NAMES.get(f[2], f[2]), f[1],
                                                      DATATYPE_NAMES[types[0]], offset))
    if c["point_step"] != OUSTER_POINT_STEP:
        problems.append("point_step %d (need %d)" % (c["point_step"], OUSTER_POINT_STEP))
    if c["is_bigendian"]:
        problems.append("big-endian")
    if c["height"] != OS1_ROWS:
        problems.append("%d rows (need %d: organized:=true, v_reduction 1)" % (c["height"], OS1_ROWS))
    if c["width"] not in OS1_WIDTHS:
        problems.append("%d columns (need one of %s)" % (c["width"], "/".join(str(w) for w in OS1_WIDTHS)))
    if c["row_step"] != c["point_step"] * c["width"] or c["data_len"] != c["row_step"] * c["height"]:
        problems.append("sizes do not add up (row_step %d, %d B of data)" % (c["row_step"], c["data_len"]))
    if c["frame_id"] != obs.lidar_frame:
        problems.append("frame %r (need %s)" % (c["frame_id"], obs.lidar_frame))
    shape = "%d x %d, %d B/point" % (c["height"], c["width"], c["point_step"])
    if problems:
        return (FAIL, shape + ": " + "; ".join(problems),
                "run ouster-ros with point_type:=original organized:=true destagger:=true point_cloud_frame:=os_sensor "
                "(robot.launch drivers:=true sets them)")
    return PASS, shape + ", ouster-ros original layout, frame %s" % c["frame_id"], ""


def check_lidar_imu(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """/ouster/imu at 100 Hz."""
    return _rate_check(obs, "imu", "/ouster/imu", lim.imu_min_rate, 0.5, lim.imu_max_lag, lim.max_future,
                       "no OS1 IMU: ouster-ros proc_mask must contain IMU",
                       "OS1 IMU slower than 100 Hz: UDP packets lost (the OS1's link, udp_dest)",
                       "IMU stamps are not ROS time: ouster-ros timestamp_mode:=TIME_FROM_ROS_TIME")


def covariance_problem(cov: Sequence[float], lim: Limits) -> Optional[str]:
    """A text if a 6 x 6 pose covariance is not sane (NaN, asymmetric, negative or huge variances, all zero)."""
    c = np.asarray(cov, dtype=float)
    if c.size != 36:
        return "covariance of %d numbers" % c.size
    c = c.reshape(6, 6)
    if not np.all(np.isfinite(c)):
        return "covariance has NaN/inf"
    if not np.allclose(c, c.T, atol=1e-9 + 1e-6 * np.abs(c).max()):
        return "covariance not symmetric"
    diag = np.diag(c)
    if np.any(diag < 0):
        return "negative variance"
    if not np.any(diag > 0):
        return "covariance all zero"
    if np.any(diag[:3] > lim.zed2_max_position_var) or np.any(diag[3:] > lim.zed2_max_orientation_var):
        return "variance too large (position sd %.2f m, orientation sd %.2f rad)" % (
            math.sqrt(diag[:3].max()), math.sqrt(diag[3:].max()))
    return None


def check_zed2(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """ZED2 pose at its grab rate, stamped in ROS time, with a sane covariance."""
    status, value, hint = _rate_check(
        obs, "zed2", "/zed2/zed_node/pose_with_covariance", lim.zed2_min_rate, 0.5, lim.zed2_max_lag, lim.max_future,
        "no ZED2 pose: is zed-ros-wrapper running (camera_name zed2, positional tracking on) and the camera on USB 3?",
        "ZED2 pose slower than 10 Hz: the Jetson is overloaded (grab_frame_rate 15)",
        "ZED2 stamps are not this host's ROS time: sync the clocks (chrony)")
    if status != PASS:
        return status, value, hint
    problem = covariance_problem(obs.zed2_covariance, lim) if obs.zed2_covariance is not None else "no covariance"
    if problem:
        return FAIL, value + ", " + problem, "the ZED2's tracking is lost or not initialised: restart its tracking"
    sd = np.sqrt(np.diag(np.asarray(obs.zed2_covariance, dtype=float).reshape(6, 6)))
    return PASS, value + ", sd %.3f m / %.3f rad" % (sd[:3].max(), sd[3:].max()), ""


def _check_frame(obs: Observation, frame: str, hint: str) -> Tuple[str, str, str]:
    t = obs.frames.get(frame)
    if t is None or isinstance(t, str):
        return FAIL, "%s -> %s missing%s" % (obs.base_frame, frame, (": " + t) if t else ""), hint
    return PASS, format_mount(t), ""


def check_tf_lidar(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """TF base_link -> os_sensor (the LiDAR's mount)."""
    return _check_frame(obs, obs.lidar_frame,
                        "robot_state_publisher with rbd_bringup's robot_description (a1_urdf + mounts.yaml) must run")


def check_tf_zed2(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """TF base_link -> zed2_camera_center (the ZED2's mount)."""
    return _check_frame(obs, obs.zed2_frame,
                        "robot_state_publisher with rbd_bringup's robot_description (a1_urdf + mounts.yaml) must run")


def tf_clashes(edges: Sequence[Tuple[str, str, str, bool]]) -> List[str]:
    """Frames with two parents, or with one parent from two publishers: one text each."""
    by_child = {}  # child -> {parent: {publisher}}
    for parent, child, publisher, _static in edges:
        by_child.setdefault(child.lstrip("/"), {}).setdefault(parent.lstrip("/"), set()).add(publisher)
    out = []
    for child in sorted(by_child):
        parents = by_child[child]
        if len(parents) > 1:
            out.append("%s has %d parents: %s" % (child, len(parents), ", ".join(
                "%s (%s)" % (p, ", ".join(sorted(pubs))) for p, pubs in sorted(parents.items()))))
        else:
            ((parent, pubs),) = parents.items()
            if len(pubs) > 1:
                out.append("%s -> %s published by %d nodes: %s" % (parent, child, len(pubs), ", ".join(sorted(pubs))))
    return out


def check_tf_parents(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """Every TF frame has one parent and one publisher."""
    if not obs.tf_edges:
        return FAIL, "no transforms on /tf or /tf_static", "nothing publishes TF: start the robot stack"
    clashes = tf_clashes(obs.tf_edges)
    frames = len({e[1] for e in obs.tf_edges})
    if clashes:
        return (FAIL, "; ".join(clashes),
                "one publisher per frame: zed-ros-wrapper publish_urdf:=false and pos_tracking publish_tf/"
                "publish_map_tf false (robot.launch drivers:=true sets them); stop the other publisher")
    return PASS, "%d frames, each with one parent and one publisher" % frames, ""


def check_zone(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """/rbd_lidar/state fresh, not stale, no error."""
    s = obs.stream("zone")
    if s.count == 0:
        return FAIL, "no /rbd_lidar/state in %.1f s" % obs.duration, "rbd_lidar is not running"
    age = s.age(obs.now)
    last = obs.zone_last or {}
    value = "%s, last %.2f s ago" % (_fmt_rate(s), age)
    if last.get("stale"):
        return FAIL, value + ", stale", "rbd_lidar gets no valid cloud: see its log and the /ouster/points lines"
    if last.get("error"):
        return FAIL, value + ", error: %s" % last["error"], "rbd_lidar rejects the cloud: see the layout line"
    if age > lim.zone_max_age:
        return FAIL, value + " (stale after %.1f s)" % lim.zone_max_age, "rbd_lidar stalls: see its log"
    occupied = last.get("collision")
    return PASS, value + (", zone OCCUPIED (%s points)" % "/".join(str(p) for p in last.get("points", ()))
                          if occupied else ", zone clear"), ""


def check_pose(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """/rbd_localization/pose fresh at >= 10 Hz."""
    return _rate_check(obs, "pose", "/rbd_localization/pose", lim.pose_min_rate, lim.pose_max_age, 0.5, lim.max_future,
                       "no localization pose: rbd_localization (EKF + map correction) is not running or has no input",
                       "localization pose slower than 10 Hz: the EKF lacks input (IMU, ZED2) or the CPU is overloaded",
                       "pose stamps are not ROS time")


def check_floor(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """The floor the LiDAR sees lies where the mounts and the legs put it."""
    t = obs.frames.get(obs.lidar_frame)
    if obs.cloud_xyz is None or t is None or isinstance(t, str):
        return SKIP, "no cloud or no %s transform" % obs.lidar_frame, ""
    (x, y, z), q = t
    pts = np.asarray(obs.cloud_xyz, dtype=float).reshape(-1, 3).dot(quaternion_matrix(q).T) + np.array([x, y, z])
    feet = [obs.frames.get(f) for f in FEET]
    contacts = None
    if all(f is not None and not isinstance(f, str) for f in feet):
        contacts = np.array([f[0] for f in feet], dtype=float) - np.array([0.0, 0.0, FOOT_RADIUS])
    status, value, hint, _numbers = floor_check(pts, contacts, lim)
    return status, value, hint


def check_bridge(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """rbd_bridge up and accepting WebSocket connections; who is connected."""
    b = obs.bridge
    if b is None or not b.get("node"):
        return FAIL, "rbd_bridge is not running", "the laptop app cannot connect: start the robot stack"
    where = "ws://%s:%s" % (b.get("host"), b.get("port"))
    if not b.get("listening"):
        return FAIL, "%s not answering: %s" % (where, b.get("error") or "?"), (
            "check rbd_bridge's log, bridge_address/bridge_port and the firewall")
    clients = b.get("clients")
    if clients:
        who = "%d client(s): %s" % (len(clients), ", ".join(clients))
    elif clients is not None or b.get("client_count") == 0:
        who = "no clients connected"
    else:
        who = "%s client(s)" % b.get("client_count", "?")
    return PASS, "%s listening, %s" % (where, who), ""


def clock_spread(clocks: Dict[str, Tuple[float, float, str]]) -> Tuple[float, Tuple[str, str]]:
    """Worst case between two hosts: |offset_i - offset_j| + uncertainty_i + uncertainty_j [s], and the pair."""
    worst, pair = 0.0, ("", "")
    hosts = sorted(clocks)
    for i, a in enumerate(hosts):
        for b in hosts[i + 1:]:
            (oa, ua, _), (ob, ub, _) = clocks[a], clocks[b]
            w = abs(oa - ob) + ua + ub
            if w > worst:
                worst, pair = w, (a, b)
    return worst, pair


def check_clocks(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """The clocks of all ROS hosts agree within 50 ms (only when the graph spans hosts)."""
    if obs.clocks is None:
        return SKIP, "not measured", ""
    errors = {h: v for h, v in obs.clocks.items() if isinstance(v, str)}
    good = {h: v for h, v in obs.clocks.items() if not isinstance(v, str)}
    if len(obs.clocks) <= 1:
        return PASS, "one ROS host (%s): nothing to compare" % (", ".join(obs.clocks) or "-"), ""
    detail = ", ".join("%s %+.1f +- %.1f ms" % (h, 1000 * o, 1000 * u) for h, (o, u, _s) in sorted(good.items()))
    if errors:
        return (FAIL, "cannot read the clock of %s%s" % (
            "; ".join("%s (%s)" % kv for kv in sorted(errors.items())), ("; " + detail) if detail else ""),
            "preflight reads a host's clock from the HTTP Date of its roslaunch/rospy XML-RPC servers: start "
            "that host's nodes with roslaunch, and sync the clocks with chrony (rbd_bringup README)")
    worst, (a, b) = clock_spread(good)
    value = "%d hosts: %s (vs this host)" % (len(good), detail)
    if worst > lim.clock_max_skew:
        return (FAIL, value + "; %s vs %s up to %.0f ms" % (a, b, 1000 * worst),
                "sync the clocks: chrony with the Jetson as server (rbd_bringup README, Clocks); TF and the "
                "staleness checks compare stamps across hosts")
    return PASS, value, ""


#: (key, name, check, keys it needs: SKIP when one of them did not pass)
CHECKS = [
    ("a1_state", "A1 HighState", check_a1_state, ()),
    ("a1_layout", "A1 SDK layout", check_a1_layout, ()),
    ("a1_cmd", "A1 HighCmd", check_a1_cmd, ()),
    ("estop", "E-stop chain", check_estop, ()),
    ("lidar_cloud", "LiDAR /ouster/points", check_lidar_cloud, ()),
    ("lidar_layout", "LiDAR cloud layout", check_lidar_layout, ()),
    ("lidar_imu", "LiDAR /ouster/imu", check_lidar_imu, ()),
    ("zed2", "ZED2 pose", check_zed2, ()),
    ("tf_lidar", "TF base_link->os_sensor", check_tf_lidar, ()),
    ("tf_zed2", "TF base_link->ZED2", check_tf_zed2, ()),
    ("tf_parents", "TF one parent per frame", check_tf_parents, ()),
    ("zone", "LiDAR zone state", check_zone, ("lidar_cloud", "lidar_layout", "tf_lidar")),
    ("pose", "Localization pose", check_pose, ()),
    ("floor", "Floor vs mounts", check_floor, ("lidar_layout", "tf_lidar")),
    ("bridge", "Bridge", check_bridge, ()),
    ("clocks", "Clocks of ROS hosts", check_clocks, ()),
]


def evaluate(obs: Observation, limits: Optional[Limits] = None) -> List[Row]:
    """Run every check on ``obs``; one :class:`Row` per check, in table order."""
    lim = limits or Limits()
    rows = []  # type: List[Row]
    names = {key: name for key, name, _f, _n in CHECKS}
    done = {}  # type: Dict[str, str]
    for key, name, check, needs in CHECKS:
        blocked = [n for n in needs if done.get(n) != PASS]
        if blocked:
            row = Row(key, name, SKIP, "needs: %s" % ", ".join(names[n] for n in blocked))
        else:
            try:
                status, value, hint = check(obs, lim)
            except Exception as exc:  # a bug in one check must not hide the others
                status, value, hint = FAIL, "check failed: %r" % (exc,), "report this preflight bug"
            row = Row(key, name, status, value, hint)
        done[key] = row.status
        rows.append(row)
    return rows


def passed(rows: Sequence[Row]) -> bool:
    """True only if every row passed."""
    return bool(rows) and all(r.status == PASS for r in rows)


def mounts_in_use(obs: Observation) -> List[Tuple[str, str]]:
    """(frame, mount text) of the sensor frames and the zone origin, as TF has them."""
    out = []
    for frame in (obs.lidar_frame, obs.zed2_frame, "collision_zone"):
        t = obs.frames.get(frame)
        out.append((frame, format_mount(t) if t is not None and not isinstance(t, str) else "missing"))
    return out


def render(rows: Sequence[Row], obs: Optional[Observation] = None, colour: bool = False) -> str:
    """The table as text: one line per check (status, check, measured value, what to do on FAIL)."""
    width = max(len(r.name) for r in rows) if rows else 10
    paint = {PASS: "\033[32m%s\033[0m", FAIL: "\033[1;31m%s\033[0m", SKIP: "\033[33m%s\033[0m"}
    lines = []
    for r in rows:
        status = paint[r.status] % r.status if colour else r.status
        line = "%s  %-*s  %s" % (status, width, r.name, r.value)
        if r.status == FAIL and r.hint:
            line += "  -> %s" % r.hint
        lines.append(line)
    n_fail = sum(1 for r in rows if r.status == FAIL)
    n_skip = sum(1 for r in rows if r.status == SKIP)
    if obs is not None:
        lines.append("")
        lines.append("Mounts in use%s:" % (" (%s)" % obs.mounts_file if obs.mounts_file else ""))
        for frame, text in mounts_in_use(obs):
            lines.append("  %s -> %-20s %s" % (obs.base_frame, frame, text))
    lines.append("")
    lines.append("preflight: %s (%d checks, %d failed, %d skipped)" % (
        "READY" if passed(rows) else "NOT READY", len(rows), n_fail, n_skip))
    return "\n".join(lines)

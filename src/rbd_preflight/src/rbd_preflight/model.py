"""The preflight report model: the observation the collector fills, the limits, the rows."""

from typing import List, Optional, Sequence

PASS, FAIL, SKIP = "PASS", "FAIL", "SKIP"


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
        localized: the last ``/rbd_localization/localized`` (latched), None if none arrived.
        map_mode: ``mode`` of the last map correction diagnostics (``mapping`` or
            ``localization (FILE)``), None if none arrived.
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
        self.localized = None  # type: Optional[bool]
        self.map_mode = None  # type: Optional[str]
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


def passed(rows: Sequence[Row]) -> bool:
    """True only if every row passed."""
    return bool(rows) and all(r.status == PASS for r in rows)

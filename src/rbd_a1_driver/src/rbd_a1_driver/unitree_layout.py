"""Unitree legged SDK v3.3 high-level structs, packed byte for byte (the one place that knows the layout).

The A1's high-level LCM server (``lcm_server_high`` of unitree_legged_sdk v3.3 / 3.3.4) relays the raw
bytes of ``HighCmd`` from channel ``LCM_High_Cmd`` to the robot over UDP and the raw bytes of
``HighState`` from the robot to ``LCM_High_State``. Both structs are ``#pragma pack(1)`` and
little-endian, so a Python ``struct`` format with ``<`` reproduces them exactly:

* ``HighCmd``   113 bytes (v3.2 was 143 bytes with a different field order: not compatible).
* ``HighState`` 265 bytes (v3.2: 256 bytes).

v3.3 is chosen because it is the last SDK release for the A1 (3.3.3+ is A1-only, A1_sport >= v1.20)
and unitree_ros_to_real points A1 users to 3.3.4; its ``velocity`` and ``yawSpeed`` are SI units
(m/s, rad/s), unlike v3.2's "-1..1 scale" fields.

Semantics used by the driver and by the mock A1 (rbd_sim):

* ``HighCmd.bodyHeight`` is a change from the nominal standing height (0.28 m) [m];
  ``HighState.bodyHeight`` is the absolute body height above the ground [m].
* ``HighCmd.euler`` is (roll, pitch, yaw) of the body in force-stand mode [rad].
* ``HighState.position`` is the robot's own (drifting) odometry in its power-up frame [m];
  ``HighState.velocity`` is (forward, side, vertical) in the body frame [m/s]; ``yawSpeed`` [rad/s].
* ``crc`` is left 0: the SDK's UDP layer computes it when the LCM server forwards the command;
  nothing on the LCM side checks it.
"""

import math
import struct

# levelFlag of a high-level packet in SDK v3.3 (comm.h: HIGHLEVEL = 0x00).
HIGHLEVEL = 0x00

# HighCmd.mode values (SDK v3.3 comm.h).
MODE_IDLE = 0  # idle, default stand
MODE_FORCE_STAND = 1  # force stand, body attitude from euler + bodyHeight
MODE_VELOCITY_WALK = 2  # walk with velocity[0..1] + yawSpeed
MODE_POSITION_WALK = 3
MODE_PATH_WALK = 4
MODE_STAND_DOWN = 5
MODE_STAND_UP = 6
MODE_DAMPING = 7
MODE_RECOVERY = 8
MODE_BACKFLIP = 9
MODE_JUMP_YAW = 10
MODE_STRAIGHT_HAND = 11
MODE_DANCE1 = 12
MODE_DANCE2 = 13
MAX_MODE = MODE_DANCE2

# HighCmd.gaitType values.
GAIT_IDLE = 0
GAIT_TROT = 1
GAIT_TROT_RUNNING = 2
GAIT_CLIMB_STAIR = 3
MAX_GAIT = GAIT_CLIMB_STAIR

MAX_SPEED_LEVEL = 2

NOMINAL_BODY_HEIGHT = 0.28  # [m], SDK default standing height

HIGH_CMD_SIZE = 113
HIGH_STATE_SIZE = 265

CHANNEL_HIGH_CMD = "LCM_High_Cmd"
CHANNEL_HIGH_STATE = "LCM_High_State"
DEFAULT_LCM_URL = "udpm://239.255.76.67:7667?ttl=0"


class LayoutError(ValueError):
    """A packet that is not a valid high-level struct (wrong size, bad header, bad values)."""


# A struct as a table: (attribute, struct codes, default). A field with one code is a scalar,
# with several a tuple; "12s"/"40s" are byte strings. The formats below are built from these
# tables, so the order of the attributes is the byte order of the SDK struct.
_HEADER_FIELDS = (
    ("level_flag", "B", HIGHLEVEL),
    ("comm_version", "H", 0),
    ("robot_id", "H", 0),
    ("sn", "I", 0),
    ("band_width", "B", 0),
    ("mode", "B", MODE_IDLE),
)
_TRAILER_FIELDS = (
    ("wireless_remote", "40s", b"\x00" * 40),
    ("reserve", "I", 0),
    ("crc", "I", 0),
)

_HIGH_CMD_FIELDS = (
    _HEADER_FIELDS
    + (
        ("gait_type", "B", GAIT_IDLE),
        ("speed_level", "B", 0),
        ("foot_raise_height", "f", 0.0),  # change from the default 0.08 m [m]
        ("body_height", "f", 0.0),  # change from NOMINAL_BODY_HEIGHT [m]
        ("position", "2f", (0.0, 0.0)),  # mode 3 target [m]
        ("euler", "3f", (0.0, 0.0, 0.0)),  # roll, pitch, yaw in force stand [rad]
        ("velocity", "2f", (0.0, 0.0)),  # forward, side in the body frame [m/s]
        ("yaw_speed", "f", 0.0),  # [rad/s]
        ("led", "12s", b"\x00" * 12),  # 4 LEDs x (r, g, b)
    )
    + _TRAILER_FIELDS
)

_HIGH_STATE_FIELDS = (
    _HEADER_FIELDS
    + (
        ("progress", "f", 0.0),
        ("quaternion", "4f", (1.0, 0.0, 0.0, 0.0)),  # w, x, y, z
        ("gyroscope", "3f", (0.0, 0.0, 0.0)),  # body rates [rad/s]
        ("accelerometer", "3f", (0.0, 0.0, 9.81)),  # specific force in the body frame [m/s^2]
        ("rpy", "3f", (0.0, 0.0, 0.0)),  # [rad]
        ("temperature", "b", 30),
        ("gait_type", "B", GAIT_IDLE),
        ("foot_raise_height", "f", 0.08),
        ("position", "3f", (0.0, 0.0, 0.0)),  # own odometry [m]
        ("body_height", "f", NOMINAL_BODY_HEIGHT),  # absolute [m]
        ("velocity", "3f", (0.0, 0.0, 0.0)),  # body frame [m/s]
        ("yaw_speed", "f", 0.0),  # [rad/s]
        ("foot_position", "12f", (0.0,) * 12),  # 4 x (x, y, z) relative to the body [m]
        ("foot_speed", "12f", (0.0,) * 12),
        ("foot_force", "4h", (0, 0, 0, 0)),
        ("foot_force_est", "4h", (0, 0, 0, 0)),
    )
    + _TRAILER_FIELDS
)


def _count(code: str) -> int:
    """Number of values a struct code yields: "3f" -> 3, "f" -> 1, "40s" -> 1."""
    if code.endswith("s") or len(code) == 1:
        return 1
    return int(code[:-1])


def _format(fields: tuple) -> str:
    return "<" + "".join(code for _, code, _ in fields)


_INTEGER_CODES = ("b", "B", "h", "H", "I")

# HighCmd: levelFlag commVersion robotID SN bandWidth | mode gaitType speedLevel |
# footRaiseHeight bodyHeight | position[2] | euler[3] | velocity[2] | yawSpeed | LED[4] (3 B each) |
# wirelessRemote[40] | reserve | crc
HIGH_CMD_FORMAT = _format(_HIGH_CMD_FIELDS)
# HighState: levelFlag commVersion robotID SN bandWidth | mode progress |
# IMU{quaternion[4] (w,x,y,z), gyroscope[3], accelerometer[3], rpy[3], temperature int8} |
# gaitType footRaiseHeight | position[3] | bodyHeight | velocity[3] | yawSpeed |
# footPosition2Body[4] (xyz) | footSpeed2Body[4] (xyz) | footForce[4] int16 | footForceEst[4] int16 |
# wirelessRemote[40] | reserve | crc
HIGH_STATE_FORMAT = _format(_HIGH_STATE_FIELDS)


class _Packed:
    """A packed little-endian struct described by a field table (see ``_HIGH_CMD_FIELDS``)."""

    __slots__ = ()
    _FIELDS = ()  # type: tuple
    _STRUCT = struct.Struct("<")
    _NAME = ""

    def __init__(self) -> None:
        for name, _, default in self._FIELDS:
            setattr(self, name, default)

    def pack(self) -> bytes:
        """Return the packed bytes exactly as the SDK's struct."""
        values = []  # type: list
        for name, code, _ in self._FIELDS:
            value = getattr(self, name)
            if _count(code) == 1:
                values.append(int(value) if code in _INTEGER_CODES else value)
            else:
                values.extend(value)
        return self._STRUCT.pack(*values)

    @classmethod
    def _decode(cls, data: bytes) -> "_Packed":
        if len(data) != cls._STRUCT.size:
            raise LayoutError("%s must be %d bytes, got %d" % (cls._NAME, cls._STRUCT.size, len(data)))
        values = cls._STRUCT.unpack(data)
        obj = cls()
        i = 0
        for name, code, _ in cls._FIELDS:
            n = _count(code)
            setattr(obj, name, values[i] if n == 1 else tuple(values[i : i + n]))
            i += n
        return obj


class HighCmd(_Packed):
    """The SDK v3.3 HighCmd (all fields; attribute names are the SDK's in snake_case)."""

    __slots__ = tuple(name for name, _, _ in _HIGH_CMD_FIELDS)
    _FIELDS = _HIGH_CMD_FIELDS
    _STRUCT = struct.Struct(_format(_HIGH_CMD_FIELDS))
    _NAME = "HighCmd"

    def floats(self) -> tuple:
        """All float fields, for finiteness checks."""
        return (
            (self.foot_raise_height, self.body_height, self.yaw_speed)
            + tuple(self.position)
            + tuple(self.euler)
            + tuple(self.velocity)
        )

    @classmethod
    def unpack(cls, data: bytes) -> "HighCmd":
        """Decode raw bytes; raise LayoutError on a wrong size (values are not checked here)."""
        return cls._decode(data)  # type: ignore[return-value]


def check_high_cmd(cmd: HighCmd) -> str:
    """Return "" if the decoded command is one the A1 would act on, else the reason it is rejected.

    Rejects: a levelFlag other than HIGHLEVEL, unknown mode / gaitType / speedLevel, and any
    non-finite float (NaN or inf). Finite but large values are not rejected here: the robot
    saturates them.
    """
    if cmd.level_flag != HIGHLEVEL:
        return "levelFlag 0x%02x is not HIGHLEVEL (0x%02x)" % (cmd.level_flag, HIGHLEVEL)
    if cmd.mode > MAX_MODE:
        return "unknown mode %d" % cmd.mode
    if cmd.gait_type > MAX_GAIT:
        return "unknown gaitType %d" % cmd.gait_type
    if cmd.speed_level > MAX_SPEED_LEVEL:
        return "unknown speedLevel %d" % cmd.speed_level
    for value in cmd.floats():
        if not math.isfinite(value):
            return "non-finite value %r" % value
    return ""


def decode_high_cmd(data: bytes) -> HighCmd:
    """Decode and check a HighCmd packet; raise LayoutError with the reason if it is unusable."""
    cmd = HighCmd.unpack(data)
    reason = check_high_cmd(cmd)
    if reason:
        raise LayoutError(reason)
    return cmd


class HighState(_Packed):
    """The SDK v3.3 HighState (all fields; attribute names are the SDK's in snake_case)."""

    __slots__ = tuple(name for name, _, _ in _HIGH_STATE_FIELDS)
    _FIELDS = _HIGH_STATE_FIELDS
    _STRUCT = struct.Struct(_format(_HIGH_STATE_FIELDS))
    _NAME = "HighState"

    @classmethod
    def unpack(cls, data: bytes) -> "HighState":
        """Decode raw bytes; raise LayoutError on a wrong size or a non-finite pose/velocity value."""
        s = cls._decode(data)
        used = s.quaternion + s.gyroscope + s.accelerometer + s.rpy + s.position + s.velocity
        for value in used + (s.body_height, s.yaw_speed):
            if not math.isfinite(value):
                raise LayoutError("HighState has a non-finite value %r" % value)
        return s  # type: ignore[return-value]


assert HighCmd._STRUCT.size == HIGH_CMD_SIZE, HighCmd._STRUCT.size
assert HighState._STRUCT.size == HIGH_STATE_SIZE, HighState._STRUCT.size

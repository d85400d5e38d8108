"""Unitree legged SDK high-level structs, packed byte for byte (the driver's one place that knows them).

The A1's high-level LCM server (``lcm_server_high`` of unitree_legged_sdk) relays the raw bytes of
``HighCmd`` from channel ``LCM_High_Cmd`` to the robot over UDP and the raw bytes of ``HighState``
from the robot to ``LCM_High_State``. Both structs are ``#pragma pack(1)`` and little-endian, so a
Python ``struct`` format with ``<`` reproduces them exactly. Two SDK release lines run on A1s
(``../shared/INTERFACES.md`` §2, "Correction"):

* **v3.3 / v3.3.1**: ``HighCmd`` 113 B, ``HighState`` 265 B (``mode``, ``progress``, ``IMU`` ...).
* **3.3.3 / 3.3.4** (A1-only, A1_sport >= v1.20; the release ``unitree_ros_to_real`` points A1
  users to): the same 113 B ``HighCmd``; ``HighState`` 1025 B, which starts with ``IMU imu``,
  ``MotorState motorState[20]`` (38 B each), ``int16 footForce[4]``, ``int16 footForceEst[4]``
  and only then ``mode``, ``progress``, ``gaitType`` ...

The LCM server copies whatever struct its SDK release was built with, so the size of a packet on
``LCM_High_State`` (265 or 1025) tells the layouts apart; :class:`StateDecoder` does that.
v3.2 (143 B / 256 B, different field order) and the short-lived v3.3.2 (117 B / 319 B) are not
supported: their packets are rejected by size.

Semantics used by the driver:

* ``HighCmd.bodyHeight`` is a change from the nominal standing height (0.28 m) [m];
  ``HighState.bodyHeight`` is the absolute body height above the ground [m].
* ``HighCmd.euler`` is (roll, pitch, yaw) of the body in force-stand mode [rad];
  ``HighCmd.velocity`` [m/s] and ``yawSpeed`` [rad/s] are SI (v3.2's were "-1..1 scale").
* ``HighState.position`` is the robot's own (drifting) odometry in its power-up frame [m];
  ``HighState.velocity`` is (forward, side, vertical) in the body frame [m/s]; ``yawSpeed`` [rad/s].
* ``motorState[i]`` (3.3.4 only): motor ``i = leg * 3 + joint``, legs FR 0, FL 1, RR 2, RL 3,
  joints hip, thigh, calf; ``q`` [rad], ``dq`` [rad/s], ``tauEst`` [N m]; 12 of the 20 used.
* ``wirelessRemote[40]``: the hand-held remote; ``btn`` (uint16 at byte 2) holds one bit per
  button (SDK ``joystick.h``: bit 0 R1, L1, start, select, R2, L2, F1, F2, A, B, X, Y, up,
  right, down, left).
* ``crc`` is left 0: the SDK's UDP layer computes it when the LCM server forwards the command;
  nothing on the LCM side checks it.

The tests of this module take their truth from the vendor's offsets (``rbd_wire_oracle``), not
from here, and the mock A1 speaks the wire through its own description (``rbd_sim.unitree_wire``).
"""

import math
import struct
from typing import Optional

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

SDK_V33 = "3.3"  # v3.3 / v3.3.1
SDK_V334 = "3.3.4"  # 3.3.3 / 3.3.4
SDK_LAYOUTS = (SDK_V33, SDK_V334)
SDK_NAMES = {SDK_V33: "SDK v3.3/v3.3.1", SDK_V334: "SDK 3.3.3/3.3.4"}

HIGH_CMD_SIZE = 113  # the same in both layouts
HIGH_STATE_SIZES = {SDK_V33: 265, SDK_V334: 1025}
HIGH_STATE_SIZE = HIGH_STATE_SIZES[SDK_V33]  # v3.3 (kept for callers of the v3.3-only module)

MOTOR_COUNT = 20  # motorState[20] in 3.3.4; the A1 uses the first 12
JOINT_COUNT = 12
#: Joint names in the SDK's motor order (leg * 3 + joint), as unitree_ros' a1_description names them.
JOINT_NAMES = tuple(
    "%s_%s_joint" % (leg, joint) for leg in ("FR", "FL", "RR", "RL") for joint in ("hip", "thigh", "calf")
)

#: Bit of each button of the hand-held remote in ``wirelessRemote`` bytes 2..3 (``btn``).
REMOTE_BUTTONS = {
    "R1": 0, "L1": 1, "start": 2, "select": 3, "R2": 4, "L2": 5, "F1": 6, "F2": 7,
    "A": 8, "B": 9, "X": 10, "Y": 11, "up": 12, "right": 13, "down": 14, "left": 15,
}

CHANNEL_HIGH_CMD = "LCM_High_Cmd"
CHANNEL_HIGH_STATE = "LCM_High_State"
DEFAULT_LCM_URL = "udpm://239.255.76.67:7667?ttl=0"


class LayoutError(ValueError):
    """A packet that is not a valid high-level struct (wrong size, bad header, bad values)."""


# A struct as a table: (attribute, struct codes, default). A field with one code is a scalar,
# with several a tuple; "12s"/"40s" are byte strings. The formats below are built from these
# tables, so the order of the attributes is the byte order of the SDK struct.
_ID_FIELDS = (
    ("level_flag", "B", HIGHLEVEL),
    ("comm_version", "H", 0),
    ("robot_id", "H", 0),
    ("sn", "I", 0),
    ("band_width", "B", 0),
)
_TRAILER_FIELDS = (
    ("wireless_remote", "40s", b"\x00" * 40),
    ("reserve", "I", 0),
    ("crc", "I", 0),
)

_HIGH_CMD_FIELDS = (
    _ID_FIELDS
    + (
        ("mode", "B", MODE_IDLE),
        ("gait_type", "B", GAIT_IDLE),
        ("speed_level", "B", 0),
        ("foot_raise_height", "f", 0.0),  # change from the default 0.08 m [m]
        ("body_height", "f", 0.0),  # change from NOMINAL_BODY_HEIGHT [m]
        ("position", "2f", (0.0, 0.0)),  # mode 3 target [m] (the SDK spells it "postion")
        ("euler", "3f", (0.0, 0.0, 0.0)),  # roll, pitch, yaw in force stand [rad]
        ("velocity", "2f", (0.0, 0.0)),  # forward, side in the body frame [m/s]
        ("yaw_speed", "f", 0.0),  # [rad/s]
        ("led", "12s", b"\x00" * 12),  # 4 LEDs x (r, g, b)
    )
    + _TRAILER_FIELDS
)

_IMU_FIELDS = (
    ("quaternion", "4f", (1.0, 0.0, 0.0, 0.0)),  # w, x, y, z
    ("gyroscope", "3f", (0.0, 0.0, 0.0)),  # body rates [rad/s]
    ("accelerometer", "3f", (0.0, 0.0, 9.81)),  # specific force in the body frame [m/s^2]
    ("rpy", "3f", (0.0, 0.0, 0.0)),  # [rad]
    ("temperature", "b", 30),
)
_LOCOMOTION_FIELDS = (
    ("gait_type", "B", GAIT_IDLE),
    ("foot_raise_height", "f", 0.08),
    ("position", "3f", (0.0, 0.0, 0.0)),  # own odometry [m]
    ("body_height", "f", NOMINAL_BODY_HEIGHT),  # absolute [m]
    ("velocity", "3f", (0.0, 0.0, 0.0)),  # body frame [m/s]
    ("yaw_speed", "f", 0.0),  # [rad/s]
    ("foot_position", "12f", (0.0,) * 12),  # footPosition2Body: 4 x (x, y, z) relative to the body [m]
    ("foot_speed", "12f", (0.0,) * 12),  # footSpeed2Body [m/s]
)
_FOOT_FORCE_FIELDS = (
    ("foot_force", "4h", (0, 0, 0, 0)),
    ("foot_force_est", "4h", (0, 0, 0, 0)),
)

# MotorState (38 B): mode u8, q, dq, ddq, tauEst, q_raw, dq_raw, ddq_raw (f32), temperature i8,
# reserve u32[2]. Kept as raw bytes in the table and decoded per motor by joints().
_MOTOR_STRUCT = struct.Struct("<BfffffffbII")
_MOTOR_BYTES = MOTOR_COUNT * _MOTOR_STRUCT.size

# v3.3 / v3.3.1: header, mode, progress, IMU, locomotion, foot forces, remote, reserve, crc.
_HIGH_STATE_FIELDS = (
    _ID_FIELDS
    + (("mode", "B", MODE_IDLE), ("progress", "f", 0.0))
    + _IMU_FIELDS
    + _LOCOMOTION_FIELDS
    + _FOOT_FORCE_FIELDS
    + _TRAILER_FIELDS
)
# 3.3.3 / 3.3.4: header, IMU, motorState[20], foot forces, mode, progress, locomotion, remote, ...
_HIGH_STATE_334_FIELDS = (
    _ID_FIELDS
    + _IMU_FIELDS
    + (("motor_state", "%ds" % _MOTOR_BYTES, b"\x00" * _MOTOR_BYTES),)
    + _FOOT_FORCE_FIELDS
    + (("mode", "B", MODE_IDLE), ("progress", "f", 0.0))
    + _LOCOMOTION_FIELDS
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
# HighState v3.3: levelFlag commVersion robotID SN bandWidth | mode progress |
# IMU{quaternion[4] (w,x,y,z), gyroscope[3], accelerometer[3], rpy[3], temperature int8} |
# gaitType footRaiseHeight | position[3] | bodyHeight | velocity[3] | yawSpeed |
# footPosition2Body[4] (xyz) | footSpeed2Body[4] (xyz) | footForce[4] int16 | footForceEst[4] int16 |
# wirelessRemote[40] | reserve | crc
HIGH_STATE_FORMAT = _format(_HIGH_STATE_FIELDS)
# HighState 3.3.4: levelFlag commVersion robotID SN bandWidth | IMU | MotorState motorState[20] |
# footForce[4] footForceEst[4] int16 | mode progress | gaitType footRaiseHeight | position[3] |
# bodyHeight | velocity[3] | yawSpeed | footPosition2Body[4] | footSpeed2Body[4] |
# wirelessRemote[40] | reserve | crc
HIGH_STATE_334_FORMAT = _format(_HIGH_STATE_334_FIELDS)

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


class _HighStateBase(_Packed):
    """What both HighState layouts have (attribute names are the SDK's in snake_case)."""

    __slots__ = ()
    SDK = ""

    @classmethod
    def unpack(cls, data: bytes) -> "_HighStateBase":
        """Decode raw bytes; raise LayoutError on a wrong size or a non-finite pose/velocity value."""
        s = cls._decode(data)
        used = s.quaternion + s.gyroscope + s.accelerometer + s.rpy + s.position + s.velocity
        for value in used + (s.body_height, s.yaw_speed):
            if not math.isfinite(value):
                raise LayoutError("HighState has a non-finite value %r" % value)
        return s  # type: ignore[return-value]

    def buttons(self) -> int:
        """The remote's button bits (``btn`` of ``wirelessRemote``; see :data:`REMOTE_BUTTONS`)."""
        return remote_buttons(self.wireless_remote)


class HighState(_HighStateBase):
    """The SDK v3.3 / v3.3.1 HighState, 265 B."""

    __slots__ = tuple(name for name, _, _ in _HIGH_STATE_FIELDS)
    _FIELDS = _HIGH_STATE_FIELDS
    _STRUCT = struct.Struct(_format(_HIGH_STATE_FIELDS))
    _NAME = "HighState (SDK v3.3)"
    SDK = SDK_V33


class HighState334(_HighStateBase):
    """The SDK 3.3.3 / 3.3.4 HighState, 1025 B: adds motorState[20] in front of mode."""

    __slots__ = tuple(name for name, _, _ in _HIGH_STATE_334_FIELDS)
    _FIELDS = _HIGH_STATE_334_FIELDS
    _STRUCT = struct.Struct(_format(_HIGH_STATE_334_FIELDS))
    _NAME = "HighState (SDK 3.3.4)"
    SDK = SDK_V334

    def joints(self) -> tuple:
        """(q, dq, tau_est) of the 12 leg motors in SDK order [rad, rad/s, N m], three 12-tuples."""
        motors = list(_MOTOR_STRUCT.iter_unpack(self.motor_state))[:JOINT_COUNT]
        return tuple(m[1] for m in motors), tuple(m[2] for m in motors), tuple(m[4] for m in motors)


HIGH_STATE_CLASSES = {SDK_V33: HighState, SDK_V334: HighState334}
_LAYOUT_BY_SIZE = {size: layout for layout, size in HIGH_STATE_SIZES.items()}


def known_sizes() -> str:
    """The HighState sizes this module knows, for error messages."""
    return " and ".join("%d B (%s)" % (HIGH_STATE_SIZES[k], SDK_NAMES[k]) for k in SDK_LAYOUTS)


def remote_buttons(wireless_remote: bytes) -> int:
    """``btn`` (uint16 at byte 2) of the 40 ``wirelessRemote`` bytes."""
    return struct.unpack_from("<H", wireless_remote, 2)[0]


#: ``btn`` sits this many bytes before the end of a HighState of either layout: both end with
#: wirelessRemote[40] | reserve (4) | crc (4), and ``btn`` is at byte 2 of wirelessRemote.
_BTN_FROM_END = 40 + 4 + 4 - 2


def state_buttons(data: bytes) -> Optional[int]:
    """The remote's button bits of a raw HighState packet, without decoding the rest of it.

    Returns:
        ``btn`` of ``wirelessRemote`` (see :data:`REMOTE_BUTTONS`), or None if ``data`` has none
        of the known HighState sizes.
    """
    if len(data) not in _LAYOUT_BY_SIZE:
        return None
    return struct.unpack_from("<H", data, len(data) - _BTN_FROM_END)[0]


def button_mask(names: tuple) -> int:
    """Bit mask of remote buttons by name (e.g. ("L2", "B") -> 0x0220); ValueError on an unknown name."""
    mask = 0
    for name in names:
        if name not in REMOTE_BUTTONS:
            raise ValueError("unknown remote button %r (known: %s)" % (name, ", ".join(REMOTE_BUTTONS)))
        mask |= 1 << REMOTE_BUTTONS[name]
    return mask


class StateDecoder:
    """Decodes LCM_High_State packets of either SDK layout, chosen by size or forced.

    Args:
        sdk_layout: ``"auto"`` (each packet by its size: 265 B -> v3.3, 1025 B -> 3.3.4), or
            ``"3.3"`` / ``"3.3.4"`` (packets of the other size are rejected).

    Raises:
        ValueError: unknown ``sdk_layout``.
    """

    def __init__(self, sdk_layout: str = "auto") -> None:
        if sdk_layout != "auto" and sdk_layout not in SDK_LAYOUTS:
            raise ValueError("sdk_layout must be auto, %s, got %r" % (" or ".join(SDK_LAYOUTS), sdk_layout))
        self.forced = None if sdk_layout == "auto" else sdk_layout
        self.layout = self.forced  # layout of the last good packet (or the forced one); None = unknown
        self.last_size = None  # size of the last packet, good or not [B]
        self.wrong_size = 0  # packets dropped for their size (unknown, or the other layout when forced)
        self.good = 0

    @property
    def source(self) -> str:
        """``forced`` or ``auto``."""
        return "forced" if self.forced else "auto"

    def decode(self, data: bytes) -> _HighStateBase:
        """Decode one packet; raise LayoutError (with the sizes known) if it cannot be used."""
        size = len(data)
        self.last_size = size
        layout = _LAYOUT_BY_SIZE.get(size)
        if layout is None:
            self.wrong_size += 1
            raise LayoutError("HighState of %d B dropped: known sizes are %s" % (size, known_sizes()))
        if self.forced is not None and layout != self.forced:
            self.wrong_size += 1
            raise LayoutError("HighState of %d B (%s) dropped: ~sdk_layout forces %s (%d B)" % (
                size, SDK_NAMES[layout], SDK_NAMES[self.forced], HIGH_STATE_SIZES[self.forced]))
        state = HIGH_STATE_CLASSES[layout].unpack(data)
        self.layout = layout
        self.good += 1
        return state


assert HighCmd._STRUCT.size == HIGH_CMD_SIZE, HighCmd._STRUCT.size
assert HighState._STRUCT.size == HIGH_STATE_SIZES[SDK_V33], HighState._STRUCT.size
assert HighState334._STRUCT.size == HIGH_STATE_SIZES[SDK_V334], HighState334._STRUCT.size
assert _MOTOR_STRUCT.size == 38, _MOTOR_STRUCT.size

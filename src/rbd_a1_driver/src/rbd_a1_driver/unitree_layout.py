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

# HighCmd: levelFlag commVersion robotID SN bandWidth | mode gaitType speedLevel |
# footRaiseHeight bodyHeight | postion[2] | euler[3] | velocity[2] | yawSpeed | LED[4] (3 B each) |
# wirelessRemote[40] | reserve | crc
HIGH_CMD_FORMAT = "<BHHIB" + "BBB" + "ff" + "2f" + "3f" + "2f" + "f" + "12s" + "40s" + "II"
HIGH_CMD_SIZE = 113

# HighState: levelFlag commVersion robotID SN bandWidth | mode progress |
# IMU{quaternion[4] (w,x,y,z), gyroscope[3], accelerometer[3], rpy[3], temperature int8} |
# gaitType footRaiseHeight | position[3] | bodyHeight | velocity[3] | yawSpeed |
# footPosition2Body[4] (xyz) | footSpeed2Body[4] (xyz) | footForce[4] int16 | footForceEst[4] int16 |
# wirelessRemote[40] | reserve | crc
HIGH_STATE_FORMAT = (
    "<BHHIB" + "Bf" + "4f3f3f3fb" + "Bf" + "3f" + "f" + "3f" + "f" + "12f" + "12f" + "4h" + "4h" + "40s" + "II"
)
HIGH_STATE_SIZE = 265

_HIGH_CMD = struct.Struct(HIGH_CMD_FORMAT)
_HIGH_STATE = struct.Struct(HIGH_STATE_FORMAT)
assert _HIGH_CMD.size == HIGH_CMD_SIZE, _HIGH_CMD.size
assert _HIGH_STATE.size == HIGH_STATE_SIZE, _HIGH_STATE.size

CHANNEL_HIGH_CMD = "LCM_High_Cmd"
CHANNEL_HIGH_STATE = "LCM_High_State"
DEFAULT_LCM_URL = "udpm://239.255.76.67:7667?ttl=0"


class LayoutError(ValueError):
    """A packet that is not a valid high-level struct (wrong size, bad header, bad values)."""


class HighCmd:
    """The fields of the SDK v3.3 HighCmd that the A1 uses, with SDK defaults."""

    __slots__ = (
        "level_flag",
        "comm_version",
        "robot_id",
        "sn",
        "band_width",
        "mode",
        "gait_type",
        "speed_level",
        "foot_raise_height",
        "body_height",
        "position",
        "euler",
        "velocity",
        "yaw_speed",
        "led",
        "wireless_remote",
        "reserve",
        "crc",
    )

    def __init__(self) -> None:
        self.level_flag = HIGHLEVEL
        self.comm_version = 0
        self.robot_id = 0
        self.sn = 0
        self.band_width = 0
        self.mode = MODE_IDLE
        self.gait_type = GAIT_IDLE
        self.speed_level = 0
        self.foot_raise_height = 0.0  # change from the default 0.08 m [m]
        self.body_height = 0.0  # change from NOMINAL_BODY_HEIGHT [m]
        self.position = (0.0, 0.0)  # mode 3 target [m]
        self.euler = (0.0, 0.0, 0.0)  # roll, pitch, yaw in force stand [rad]
        self.velocity = (0.0, 0.0)  # forward, side in the body frame [m/s]
        self.yaw_speed = 0.0  # [rad/s]
        self.led = b"\x00" * 12
        self.wireless_remote = b"\x00" * 40
        self.reserve = 0
        self.crc = 0

    def floats(self) -> tuple:
        """All float fields, for finiteness checks."""
        return (
            (self.foot_raise_height, self.body_height, self.yaw_speed)
            + tuple(self.position)
            + tuple(self.euler)
            + tuple(self.velocity)
        )

    def pack(self) -> bytes:
        """Return the 113 packed bytes exactly as the SDK's ``HighCmd``."""
        return _HIGH_CMD.pack(
            self.level_flag,
            self.comm_version,
            self.robot_id,
            self.sn,
            self.band_width,
            self.mode,
            self.gait_type,
            self.speed_level,
            self.foot_raise_height,
            self.body_height,
            self.position[0],
            self.position[1],
            self.euler[0],
            self.euler[1],
            self.euler[2],
            self.velocity[0],
            self.velocity[1],
            self.yaw_speed,
            self.led,
            self.wireless_remote,
            self.reserve,
            self.crc,
        )

    @classmethod
    def unpack(cls, data: bytes) -> "HighCmd":
        """Decode raw bytes; raise LayoutError on a wrong size (values are not checked here)."""
        if len(data) != HIGH_CMD_SIZE:
            raise LayoutError("HighCmd must be %d bytes, got %d" % (HIGH_CMD_SIZE, len(data)))
        v = _HIGH_CMD.unpack(data)
        cmd = cls()
        (cmd.level_flag, cmd.comm_version, cmd.robot_id, cmd.sn, cmd.band_width) = v[0:5]
        (cmd.mode, cmd.gait_type, cmd.speed_level) = v[5:8]
        (cmd.foot_raise_height, cmd.body_height) = v[8:10]
        cmd.position = tuple(v[10:12])
        cmd.euler = tuple(v[12:15])
        cmd.velocity = tuple(v[15:17])
        cmd.yaw_speed = v[17]
        (cmd.led, cmd.wireless_remote, cmd.reserve, cmd.crc) = v[18:22]
        return cmd


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


class HighState:
    """The SDK v3.3 HighState (all fields)."""

    __slots__ = (
        "level_flag",
        "comm_version",
        "robot_id",
        "sn",
        "band_width",
        "mode",
        "progress",
        "quaternion",
        "gyroscope",
        "accelerometer",
        "rpy",
        "temperature",
        "gait_type",
        "foot_raise_height",
        "position",
        "body_height",
        "velocity",
        "yaw_speed",
        "foot_position",
        "foot_speed",
        "foot_force",
        "foot_force_est",
        "wireless_remote",
        "reserve",
        "crc",
    )

    def __init__(self) -> None:
        self.level_flag = HIGHLEVEL
        self.comm_version = 0
        self.robot_id = 0
        self.sn = 0
        self.band_width = 0
        self.mode = MODE_IDLE
        self.progress = 0.0
        self.quaternion = (1.0, 0.0, 0.0, 0.0)  # w, x, y, z
        self.gyroscope = (0.0, 0.0, 0.0)  # body rates [rad/s]
        self.accelerometer = (0.0, 0.0, 9.81)  # specific force in the body frame [m/s^2]
        self.rpy = (0.0, 0.0, 0.0)  # [rad]
        self.temperature = 30
        self.gait_type = GAIT_IDLE
        self.foot_raise_height = 0.08
        self.position = (0.0, 0.0, 0.0)  # own odometry [m]
        self.body_height = NOMINAL_BODY_HEIGHT  # absolute [m]
        self.velocity = (0.0, 0.0, 0.0)  # body frame [m/s]
        self.yaw_speed = 0.0  # [rad/s]
        self.foot_position = (0.0,) * 12  # 4 x (x, y, z) relative to the body [m]
        self.foot_speed = (0.0,) * 12
        self.foot_force = (0, 0, 0, 0)
        self.foot_force_est = (0, 0, 0, 0)
        self.wireless_remote = b"\x00" * 40
        self.reserve = 0
        self.crc = 0

    def pack(self) -> bytes:
        """Return the 265 packed bytes exactly as the SDK's ``HighState``."""
        return _HIGH_STATE.pack(
            self.level_flag,
            self.comm_version,
            self.robot_id,
            self.sn,
            self.band_width,
            self.mode,
            self.progress,
            *(
                tuple(self.quaternion)
                + tuple(self.gyroscope)
                + tuple(self.accelerometer)
                + tuple(self.rpy)
                + (int(self.temperature), self.gait_type, self.foot_raise_height)
                + tuple(self.position)
                + (self.body_height,)
                + tuple(self.velocity)
                + (self.yaw_speed,)
                + tuple(self.foot_position)
                + tuple(self.foot_speed)
                + tuple(self.foot_force)
                + tuple(self.foot_force_est)
                + (self.wireless_remote, self.reserve, self.crc)
            ),
        )

    @classmethod
    def unpack(cls, data: bytes) -> "HighState":
        """Decode raw bytes; raise LayoutError on a wrong size or a non-finite pose/velocity value."""
        if len(data) != HIGH_STATE_SIZE:
            raise LayoutError("HighState must be %d bytes, got %d" % (HIGH_STATE_SIZE, len(data)))
        v = _HIGH_STATE.unpack(data)
        s = cls()
        (s.level_flag, s.comm_version, s.robot_id, s.sn, s.band_width, s.mode, s.progress) = v[0:7]
        s.quaternion = tuple(v[7:11])
        s.gyroscope = tuple(v[11:14])
        s.accelerometer = tuple(v[14:17])
        s.rpy = tuple(v[17:20])
        (s.temperature, s.gait_type, s.foot_raise_height) = v[20:23]
        s.position = tuple(v[23:26])
        s.body_height = v[26]
        s.velocity = tuple(v[27:30])
        s.yaw_speed = v[30]
        s.foot_position = tuple(v[31:43])
        s.foot_speed = tuple(v[43:55])
        s.foot_force = tuple(v[55:59])
        s.foot_force_est = tuple(v[59:63])
        (s.wireless_remote, s.reserve, s.crc) = v[63:66]
        used = s.quaternion + s.gyroscope + s.accelerometer + s.rpy + s.position + s.velocity
        for value in used + (s.body_height, s.yaw_speed):
            if not math.isfinite(value):
                raise LayoutError("HighState has a non-finite value %r" % value)
        return s

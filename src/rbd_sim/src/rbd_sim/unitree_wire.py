"""The robot's side of the Unitree SDK high-level wire, as the mock A1 speaks it (ROS-free).

This is the mock's own description of the packets the A1's ``lcm_server_high`` relays, written
for ``rbd_sim`` and deliberately not shared with ``rbd_a1_driver`` (the mock imports nothing of
the driver, so the two can disagree when one of them is wrong; the tests hold both to the
vendor facts in ``rbd_wire_oracle``). It is declared the way the SDK's ``comm.h`` declares the
structs, member by member with C types, and the byte offsets follow from ``#pragma pack(1)``
(no padding, little-endian).

Layouts (``../shared/INTERFACES.md`` §2):

* ``HighCmd`` (113 B) of SDK v3.3 .. 3.3.4, what the robot receives.
* ``HighState`` of SDK v3.3 / v3.3.1 (265 B) and of SDK 3.3.3 / 3.3.4 (1025 B: ``IMU imu``,
  ``MotorState motorState[20]``, ``footForce``, ``footForceEst`` come before ``mode``).
* The hand-held remote inside ``wirelessRemote[40]`` (``xRockerBtnDataStruct``: two head bytes,
  a 16-bit button word with R1 in bit 0 ... left in bit 15, five floats, 16 idle bytes).
"""

import math
import struct
from typing import Dict, Sequence, Tuple

_C = {"uint8_t": "B", "int8_t": "b", "uint16_t": "H", "int16_t": "h", "uint32_t": "I", "float": "f"}


class Struct:
    """A packed C struct declared as ``(member, C type or Struct, array length)`` in order.

    The members' offsets follow from the declaration (no padding); the whole struct is one
    ``struct.Struct`` format, so a packet is packed or unpacked in one call.
    """

    def __init__(self, name: str, members: Sequence[Tuple[str, object, int]]) -> None:
        self.name = name
        self.members = []  # type: list  # (name, type, n, offset, element size)
        codes = []
        offset = 0
        for member, ctype, n in members:
            if isinstance(ctype, Struct):
                size = ctype.size
                codes.append(ctype.codes * n)
            else:
                size = struct.calcsize("<" + _C[ctype])
                codes.append("%d%s" % (n, _C[ctype]))
            self.members.append((member, ctype, n, offset, size))
            offset += size * n
        self.size = offset
        self.codes = "".join(codes)
        self._struct = struct.Struct("<" + self.codes)
        self.count = len(self._struct.unpack(bytes(self._struct.size)))  # number of leaf values
        assert self._struct.size == self.size, (name, self._struct.size, self.size)

    def flatten(self, values: Dict[str, object], out: list) -> None:
        """Append the leaf values of ``values`` in declaration order (missing members: zero)."""
        for member, ctype, n, _offset, _size in self.members:
            value = values.get(member)
            if isinstance(ctype, Struct):
                items = ([value] if n == 1 else list(value)) if value is not None else []
                for item in items[:n]:
                    ctype.flatten(item, out)
                out.extend([0] * (ctype.count * (n - min(len(items), n))))
            elif value is None:
                out.extend([0] * n)
            elif n == 1:
                out.append(value)
            else:
                out.extend(bytearray(value) if isinstance(value, bytes) else value)

    def encode(self, values: Dict[str, object]) -> bytes:
        """Packed bytes; members missing from ``values`` are zero."""
        out = []  # type: list
        self.flatten(values, out)
        return self._struct.pack(*out)

    def decode(self, data: bytes) -> Dict[str, object]:
        """Member values (arrays as tuples, nested structs as dicts); ValueError on a wrong size."""
        if len(data) != self.size:
            raise ValueError("%s must be %d bytes, got %d" % (self.name, self.size, len(data)))
        values = self._struct.unpack(data)
        return self._rebuild(values, 0)[0]

    def _rebuild(self, values: tuple, i: int) -> tuple:
        out = {}  # type: Dict[str, object]
        for member, ctype, n, _offset, _size in self.members:
            if isinstance(ctype, Struct):
                items = []
                for _ in range(n):
                    item, i = ctype._rebuild(values, i)
                    items.append(item)
                out[member] = items[0] if n == 1 else tuple(items)
            else:
                out[member] = values[i] if n == 1 else values[i:i + n]
                i += n
        return out, i


CARTESIAN = Struct("Cartesian", [("x", "float", 1), ("y", "float", 1), ("z", "float", 1)])
LED = Struct("LED", [("r", "uint8_t", 1), ("g", "uint8_t", 1), ("b", "uint8_t", 1)])
IMU = Struct("IMU", [
    ("quaternion", "float", 4),  # w, x, y, z
    ("gyroscope", "float", 3),  # [rad/s]
    ("accelerometer", "float", 3),  # [m/s^2]
    ("rpy", "float", 3),  # [rad]
    ("temperature", "int8_t", 1),
])
MOTOR_STATE = Struct("MotorState", [
    ("mode", "uint8_t", 1),
    ("q", "float", 1),  # [rad]
    ("dq", "float", 1),  # [rad/s]
    ("ddq", "float", 1),
    ("tauEst", "float", 1),  # [N m]
    ("q_raw", "float", 1),
    ("dq_raw", "float", 1),
    ("ddq_raw", "float", 1),
    ("temperature", "int8_t", 1),
    ("reserve", "uint32_t", 2),
])
_HEAD = [("levelFlag", "uint8_t", 1), ("commVersion", "uint16_t", 1), ("robotID", "uint16_t", 1),
         ("SN", "uint32_t", 1), ("bandWidth", "uint8_t", 1)]
_TAIL = [("wirelessRemote", "uint8_t", 40), ("reserve", "uint32_t", 1), ("crc", "uint32_t", 1)]
_WALK = [("gaitType", "uint8_t", 1), ("footRaiseHeight", "float", 1), ("position", "float", 3),
         ("bodyHeight", "float", 1), ("velocity", "float", 3), ("yawSpeed", "float", 1),
         ("footPosition2Body", CARTESIAN, 4), ("footSpeed2Body", CARTESIAN, 4)]

HIGH_CMD = Struct("HighCmd", _HEAD + [
    ("mode", "uint8_t", 1), ("gaitType", "uint8_t", 1), ("speedLevel", "uint8_t", 1),
    ("footRaiseHeight", "float", 1), ("bodyHeight", "float", 1), ("postion", "float", 2),
    ("euler", "float", 3), ("velocity", "float", 2), ("yawSpeed", "float", 1), ("led", LED, 4),
] + _TAIL)

HIGH_STATE = {
    "3.3": Struct("HighState v3.3", _HEAD + [("mode", "uint8_t", 1), ("progress", "float", 1), ("imu", IMU, 1)]
                  + _WALK + [("footForce", "int16_t", 4), ("footForceEst", "int16_t", 4)] + _TAIL),
    "3.3.4": Struct("HighState 3.3.4", _HEAD + [("imu", IMU, 1), ("motorState", MOTOR_STATE, 20),
                                                ("footForce", "int16_t", 4), ("footForceEst", "int16_t", 4),
                                                ("mode", "uint8_t", 1), ("progress", "float", 1)]
                    + _WALK + _TAIL),
}
SDK_LAYOUTS = tuple(HIGH_STATE)

REMOTE = Struct("xRockerBtnDataStruct", [
    ("head", "uint8_t", 2), ("btn", "uint16_t", 1), ("lx", "float", 1), ("rx", "float", 1),
    ("ry", "float", 1), ("L2", "float", 1), ("ly", "float", 1), ("idle", "uint8_t", 16),
])
BUTTONS = ("R1", "L1", "start", "select", "R2", "L2", "F1", "F2", "A", "B", "X", "Y", "up", "right", "down",
           "left")  # bit 0 first

HIGHLEVEL = 0x00
MODE_IDLE, MODE_FORCE_STAND, MODE_VELOCITY_WALK, MODE_BACKFLIP, MAX_MODE = 0, 1, 2, 9, 13
GAIT_IDLE, GAIT_TROT, MAX_GAIT = 0, 1, 3
MAX_SPEED_LEVEL = 2
NOMINAL_BODY_HEIGHT = 0.28  # [m]
CHANNEL_HIGH_CMD = "LCM_High_Cmd"
CHANNEL_HIGH_STATE = "LCM_High_State"
DEFAULT_LCM_URL = "udpm://239.255.76.67:7667?ttl=0"


class WireError(ValueError):
    """A packet the robot would not act on."""


class Command:
    """A decoded HighCmd; attributes are the SDK's member names (``mode``, ``velocity``, ...)."""

    def __init__(self, values: Dict[str, object]) -> None:
        self.__dict__.update(values)


def decode_high_cmd(data: bytes) -> Command:
    """Decode a HighCmd as the robot does; raise WireError if it would not act on it.

    Rejected: a size other than 113 B, a levelFlag other than HIGHLEVEL, mode > 13, gaitType > 3,
    speedLevel > 2, any NaN/inf among the floats.
    """
    try:
        v = HIGH_CMD.decode(data)
    except ValueError as e:
        raise WireError(str(e)) from None
    if v["levelFlag"] != HIGHLEVEL:
        raise WireError("levelFlag 0x%02x is not HIGHLEVEL" % v["levelFlag"])
    if v["mode"] > MAX_MODE:
        raise WireError("unknown mode %d" % v["mode"])
    if v["gaitType"] > MAX_GAIT:
        raise WireError("unknown gaitType %d" % v["gaitType"])
    if v["speedLevel"] > MAX_SPEED_LEVEL:
        raise WireError("unknown speedLevel %d" % v["speedLevel"])
    floats = (v["footRaiseHeight"], v["bodyHeight"], v["yawSpeed"]) + v["postion"] + v["euler"] + v["velocity"]
    for x in floats:
        if not math.isfinite(x):
            raise WireError("non-finite value %r" % x)
    return Command(v)


def encode_high_state(layout: str, values: Dict[str, object]) -> bytes:
    """The HighState packet of an SDK layout (``"3.3"`` or ``"3.3.4"``); members it lacks are dropped.

    ``values`` uses the SDK member names; ``motorState`` is only in 3.3.4 and is ignored for 3.3.
    """
    s = HIGH_STATE[layout]
    names = {m[0] for m in s.members}
    return s.encode({k: v for k, v in values.items() if k in names})


def remote_bytes(buttons: Sequence[str]) -> bytes:
    """The 40 ``wirelessRemote`` bytes with these buttons held (sticks centred)."""
    btn = 0
    for name in buttons:
        btn |= 1 << BUTTONS.index(name)
    return REMOTE.encode({"btn": btn})

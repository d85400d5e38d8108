"""The Unitree legged SDK's high-level packets as the vendor defines them: a test oracle.

Every table below is a list of facts: field name (the SDK's own spelling), C type, element count
and the byte offset, written as a literal number. Nothing here is computed from, or shared
with, the code under test (``rbd_a1_driver.unitree_layout`` on the driver side,
``rbd_sim.unitree_wire`` on the robot side); this module imports neither. Tests assemble packets
from these tables byte by byte (:func:`pack`: one ``struct.pack_into`` per field at its table
offset) and read the other side's packets back the same way (:func:`unpack`).

Sources of the facts (``#pragma pack(1)``, little-endian; ``../shared/INTERFACES.md`` §2):

* SDK v3.3 / v3.3.1 (unitreerobotics/unitree_legged_sdk ca3148f,
  ``include/unitree_legged_sdk/comm.h``): ``HighCmd`` 113 B, ``HighState`` 265 B.
* SDK 3.3.3 / 3.3.4 (597a66a, the A1-only releases): ``HighCmd`` unchanged (113 B);
  ``HighState`` 1025 B with ``IMU imu`` at 10, ``MotorState motorState[20]`` at 63,
  ``int16_t footForce[4]`` at 823, ``mode`` at 839 ... ``wirelessRemote[40]`` at 977,
  ``crc`` at 1021 (offsets as published in INTERFACES.md "Correction").
* ``MotorState`` (38 B): ``uint8_t mode; float q, dq, ddq, tauEst, q_raw, dq_raw, ddq_raw;
  int8_t temperature; uint32_t reserve[2]`` -> offsets 0, 1, 5, 9, 13, 17, 21, 25, 29, 30.
  Read in unitreerobotics/unitree_legged_sdk@1cca3a3 ``include/unitree_legged_sdk/comm.h`` (the
  Go1 line) and in forks carrying the A1's v3.2/v3.3-era headers (geyang, westonrobot,
  Taucrates, marzima ``unitree_legged_sdk``): the same members in the same order in all of
  them, plain C arrays or ``std::array``. The 597a66a (3.3.4) file itself was not in the public
  index searched; its 1025 B total and ``footForce`` at 823 = 63 + 20 * 38 agree with 38 B.
  The motor index is ``leg * 3 + joint`` with legs FR 0, FL 1, RR 2, RL 3 and joints hip 0,
  thigh 1, calf 2 (SDK ``quadruped.h``: FR_0 = 0 ... RL_2 = 11).
* The hand-held remote inside ``wirelessRemote[40]``: ``xRockerBtnDataStruct`` of the SDK's
  ``joystick.h`` (v3.5.1, written for the Go1; the same remote family as the A1's): ``uint8_t
  head[2]``, ``xKeySwitchUnion btn`` (uint16, bit fields from bit 0: R1, L1, start, select, R2,
  L2, F1, F2, A, B, X, Y, up, right, down, left), ``float lx, rx, ry, L2, ly``,
  ``uint8_t idle[16]``: 24 of the 40 bytes used.
* ``LED`` = ``uint8_t r, g, b`` (3 B); ``Cartesian`` = ``float x, y, z`` (12 B);
  ``IMU`` = ``float quaternion[4]`` (w, x, y, z), ``gyroscope[3]``, ``accelerometer[3]``,
  ``rpy[3]``, ``int8_t temperature`` (53 B).
"""

import struct
from typing import Dict, List, Sequence, Tuple

# C type -> (struct code, size in bytes), little-endian, no padding (#pragma pack(1)).
C_TYPES = {
    "uint8_t": ("B", 1),
    "int8_t": ("b", 1),
    "uint16_t": ("H", 2),
    "int16_t": ("h", 2),
    "uint32_t": ("I", 4),
    "float": ("f", 4),
}


class Field:
    """One member of a packed struct: name, C type (or a nested :class:`Layout`), count, offset."""

    __slots__ = ("name", "ctype", "count", "offset")

    def __init__(self, name: str, ctype: object, count: int, offset: int) -> None:
        self.name = name
        self.ctype = ctype
        self.count = count
        self.offset = offset

    @property
    def element_size(self) -> int:
        """Size of one element [B]."""
        if isinstance(self.ctype, Layout):
            return self.ctype.size
        return C_TYPES[self.ctype][1]

    @property
    def size(self) -> int:
        """Size of the whole member [B]."""
        return self.element_size * self.count


class Layout:
    """A packed struct: its name, total size [B] and members in declaration order."""

    def __init__(self, name: str, size: int, fields: Sequence[Field]) -> None:
        self.name = name
        self.size = size
        self.fields = tuple(fields)
        self.by_name = {f.name: f for f in self.fields}

    def __getitem__(self, name: str) -> Field:
        return self.by_name[name]

    def offset(self, path: str) -> int:
        """Byte offset of a member, nested members as ``"imu.rpy"`` or ``"motorState[3].q"``."""
        layout, offset = self, 0
        for part in path.split("."):
            index = 0
            if part.endswith("]"):
                part, index_text = part[:-1].split("[")
                index = int(index_text)
            f = layout[part]
            offset += f.offset + index * f.element_size
            if isinstance(f.ctype, Layout):
                layout = f.ctype
        return offset


def _f(name: str, ctype: object, count: int, offset: int) -> Field:
    return Field(name, ctype, count, offset)


LED = Layout("LED", 3, [_f("r", "uint8_t", 1, 0), _f("g", "uint8_t", 1, 1), _f("b", "uint8_t", 1, 2)])

CARTESIAN = Layout("Cartesian", 12, [_f("x", "float", 1, 0), _f("y", "float", 1, 4), _f("z", "float", 1, 8)])

IMU = Layout("IMU", 53, [
    _f("quaternion", "float", 4, 0),
    _f("gyroscope", "float", 3, 16),
    _f("accelerometer", "float", 3, 28),
    _f("rpy", "float", 3, 40),
    _f("temperature", "int8_t", 1, 52),
])

MOTOR_STATE = Layout("MotorState", 38, [
    _f("mode", "uint8_t", 1, 0),
    _f("q", "float", 1, 1),
    _f("dq", "float", 1, 5),
    _f("ddq", "float", 1, 9),
    _f("tauEst", "float", 1, 13),
    _f("q_raw", "float", 1, 17),
    _f("dq_raw", "float", 1, 21),
    _f("ddq_raw", "float", 1, 25),
    _f("temperature", "int8_t", 1, 29),
    _f("reserve", "uint32_t", 2, 30),
])

HIGH_CMD = Layout("HighCmd (SDK v3.3 .. 3.3.4)", 113, [
    _f("levelFlag", "uint8_t", 1, 0),
    _f("commVersion", "uint16_t", 1, 1),
    _f("robotID", "uint16_t", 1, 3),
    _f("SN", "uint32_t", 1, 5),
    _f("bandWidth", "uint8_t", 1, 9),
    _f("mode", "uint8_t", 1, 10),
    _f("gaitType", "uint8_t", 1, 11),
    _f("speedLevel", "uint8_t", 1, 12),
    _f("footRaiseHeight", "float", 1, 13),
    _f("bodyHeight", "float", 1, 17),
    _f("postion", "float", 2, 21),  # sic: the SDK's spelling
    _f("euler", "float", 3, 29),
    _f("velocity", "float", 2, 41),
    _f("yawSpeed", "float", 1, 49),
    _f("led", LED, 4, 53),
    _f("wirelessRemote", "uint8_t", 40, 65),
    _f("reserve", "uint32_t", 1, 105),
    _f("crc", "uint32_t", 1, 109),
])

HIGH_STATE_V33 = Layout("HighState (SDK v3.3 / v3.3.1)", 265, [
    _f("levelFlag", "uint8_t", 1, 0),
    _f("commVersion", "uint16_t", 1, 1),
    _f("robotID", "uint16_t", 1, 3),
    _f("SN", "uint32_t", 1, 5),
    _f("bandWidth", "uint8_t", 1, 9),
    _f("mode", "uint8_t", 1, 10),
    _f("progress", "float", 1, 11),
    _f("imu", IMU, 1, 15),
    _f("gaitType", "uint8_t", 1, 68),
    _f("footRaiseHeight", "float", 1, 69),
    _f("position", "float", 3, 73),
    _f("bodyHeight", "float", 1, 85),
    _f("velocity", "float", 3, 89),
    _f("yawSpeed", "float", 1, 101),
    _f("footPosition2Body", CARTESIAN, 4, 105),
    _f("footSpeed2Body", CARTESIAN, 4, 153),
    _f("footForce", "int16_t", 4, 201),
    _f("footForceEst", "int16_t", 4, 209),
    _f("wirelessRemote", "uint8_t", 40, 217),
    _f("reserve", "uint32_t", 1, 257),
    _f("crc", "uint32_t", 1, 261),
])

HIGH_STATE_V334 = Layout("HighState (SDK 3.3.3 / 3.3.4)", 1025, [
    _f("levelFlag", "uint8_t", 1, 0),
    _f("commVersion", "uint16_t", 1, 1),
    _f("robotID", "uint16_t", 1, 3),
    _f("SN", "uint32_t", 1, 5),
    _f("bandWidth", "uint8_t", 1, 9),
    _f("imu", IMU, 1, 10),
    _f("motorState", MOTOR_STATE, 20, 63),
    _f("footForce", "int16_t", 4, 823),
    _f("footForceEst", "int16_t", 4, 831),
    _f("mode", "uint8_t", 1, 839),
    _f("progress", "float", 1, 840),
    _f("gaitType", "uint8_t", 1, 844),
    _f("footRaiseHeight", "float", 1, 845),
    _f("position", "float", 3, 849),
    _f("bodyHeight", "float", 1, 861),
    _f("velocity", "float", 3, 865),
    _f("yawSpeed", "float", 1, 877),
    _f("footPosition2Body", CARTESIAN, 4, 881),
    _f("footSpeed2Body", CARTESIAN, 4, 929),
    _f("wirelessRemote", "uint8_t", 40, 977),
    _f("reserve", "uint32_t", 1, 1017),
    _f("crc", "uint32_t", 1, 1021),
])

REMOTE = Layout("xRockerBtnDataStruct", 40, [
    _f("head", "uint8_t", 2, 0),
    _f("btn", "uint16_t", 1, 2),
    _f("lx", "float", 1, 4),
    _f("rx", "float", 1, 8),
    _f("ry", "float", 1, 12),
    _f("L2", "float", 1, 16),
    _f("ly", "float", 1, 20),
    _f("idle", "uint8_t", 16, 24),
])

#: Bit of each button in ``xRockerBtnDataStruct.btn`` (bit 0 = the first bit field declared).
BUTTON_BITS = {
    "R1": 0, "L1": 1, "start": 2, "select": 3, "R2": 4, "L2": 5, "F1": 6, "F2": 7,
    "A": 8, "B": 9, "X": 10, "Y": 11, "up": 12, "right": 13, "down": 14, "left": 15,
}

#: HighState layouts by the SDK release names RoboDog uses (``~sdk_layout``).
HIGH_STATES = {"3.3": HIGH_STATE_V33, "3.3.4": HIGH_STATE_V334}

#: Joint names in the SDK's motor order (unitree_ros ``a1_description`` naming).
JOINT_NAMES = tuple(
    "%s_%s_joint" % (leg, joint) for leg in ("FR", "FL", "RR", "RL") for joint in ("hip", "thigh", "calf")
)

HIGHLEVEL = 0x00  # levelFlag of high-level packets in SDK v3.3 .. 3.3.4 (comm.h)
MODE_FORCE_STAND = 1
MODE_VELOCITY_WALK = 2
GAIT_TROT = 1


def _codes(f: Field) -> str:
    return "<%d%s" % (f.count, C_TYPES[f.ctype][0])


def pack(layout: Layout, values: Dict[str, object]) -> bytes:
    """Assemble one packet: zero bytes, then each given member written at its table offset.

    Args:
        layout: the struct.
        values: member name -> value; scalars for count 1, sequences otherwise; nested structs
            as dicts (or a sequence of dicts for arrays); ``uint8_t`` arrays also as bytes.
            Members not given stay zero.

    Returns:
        ``layout.size`` bytes.
    """
    buf = bytearray(layout.size)
    _pack_into(layout, values, buf, 0)
    return bytes(buf)


def _pack_into(layout: Layout, values: Dict[str, object], buf: bytearray, base: int) -> None:
    for name, value in values.items():
        f = layout[name]
        if isinstance(f.ctype, Layout):
            items = [value] if f.count == 1 else list(value)
            for i, item in enumerate(items):
                _pack_into(f.ctype, item, buf, base + f.offset + i * f.ctype.size)
            continue
        if isinstance(value, (bytes, bytearray)):
            items = list(value)
        elif f.count == 1:
            items = [value]
        else:
            items = list(value)
        if len(items) != f.count:
            raise ValueError("%s.%s takes %d values, got %d" % (layout.name, name, f.count, len(items)))
        struct.pack_into(_codes(f), buf, base + f.offset, *items)


def unpack(layout: Layout, data: bytes) -> Dict[str, object]:
    """Read every member of a packet at its table offset (nested structs as dicts).

    Raises:
        ValueError: the packet is not ``layout.size`` bytes.
    """
    if len(data) != layout.size:
        raise ValueError("%s is %d bytes, got %d" % (layout.name, layout.size, len(data)))
    return _unpack_from(layout, bytes(data), 0)


def _unpack_from(layout: Layout, data: bytes, base: int) -> Dict[str, object]:
    out = {}  # type: Dict[str, object]
    for f in layout.fields:
        if isinstance(f.ctype, Layout):
            items = [_unpack_from(f.ctype, data, base + f.offset + i * f.ctype.size) for i in range(f.count)]
            out[f.name] = items[0] if f.count == 1 else items
            continue
        values = struct.unpack_from(_codes(f), data, base + f.offset)
        out[f.name] = values[0] if f.count == 1 else values
    return out


def remote(buttons: Sequence[str] = (), **sticks: float) -> bytes:
    """The 40 ``wirelessRemote`` bytes with the given buttons held (and stick values).

    Args:
        buttons: names from :data:`BUTTON_BITS`, e.g. ``("L2", "B")``.
        sticks: ``lx``, ``rx``, ``ry``, ``L2``, ``ly`` as floats.
    """
    btn = 0
    for name in buttons:
        btn |= 1 << BUTTON_BITS[name]
    values = {"btn": btn}  # type: Dict[str, object]
    values.update(sticks)
    return pack(REMOTE, values)


def buttons_held(wireless_remote: Sequence[int]) -> List[str]:
    """Names of the buttons set in 40 ``wirelessRemote`` bytes (bit order of :data:`BUTTON_BITS`)."""
    btn = unpack(REMOTE, bytes(bytearray(wireless_remote)))["btn"]
    return [name for name, bit in sorted(BUTTON_BITS.items(), key=lambda kv: kv[1]) if btn >> bit & 1]


def gaps(layout: Layout) -> List[Tuple[int, int]]:
    """Byte ranges of ``layout`` that no member covers, and overlaps as negative gaps.

    A packed struct with correct offsets has none: each member starts where the previous one
    ended and the last one ends at ``layout.size``. Returns ``(offset, length)`` pairs.
    """
    out = []
    end = 0
    for f in sorted(layout.fields, key=lambda x: x.offset):
        if f.offset != end:
            out.append((end, f.offset - end))
        end = f.offset + f.size
    if end != layout.size:
        out.append((end, layout.size - end))
    return out

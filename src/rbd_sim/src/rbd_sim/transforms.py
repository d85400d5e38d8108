"""Small rigid-transform helpers (numpy, ROS-free). Quaternions are (x, y, z, w) as in ROS."""

import math

import numpy as np


def quat_to_matrix(q: tuple) -> np.ndarray:
    """3x3 rotation matrix of a quaternion (x, y, z, w); normalises it first.

    Raises:
        ValueError: zero-length or non-finite quaternion.
    """
    x, y, z, w = (float(v) for v in q)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(n) or n < 1e-9:
        raise ValueError("invalid quaternion %r" % (q,))
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def rpy_to_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rotation matrix R = Rz(yaw) Ry(pitch) Rx(roll) (ROS fixed-axis roll, pitch, yaw)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def rpy_to_quat(roll: float, pitch: float, yaw: float) -> tuple:
    """Quaternion (x, y, z, w) of roll, pitch, yaw [rad]."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def matrix_to_rpy(r: np.ndarray) -> tuple:
    """Roll, pitch, yaw [rad] of a rotation matrix (inverse of :func:`rpy_to_matrix`)."""
    pitch = math.asin(max(-1.0, min(1.0, -float(r[2, 0]))))
    roll = math.atan2(float(r[2, 1]), float(r[2, 2]))
    yaw = math.atan2(float(r[1, 0]), float(r[0, 0]))
    return roll, pitch, yaw


def quat_to_rpy(q: tuple) -> tuple:
    """Roll, pitch, yaw [rad] of a quaternion (x, y, z, w)."""
    return matrix_to_rpy(quat_to_matrix(q))


def matrix_to_quat(r: np.ndarray) -> tuple:
    """Quaternion (x, y, z, w) of a rotation matrix."""
    m = np.asarray(r, dtype=float)
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = ((m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s)
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        q = (0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s)
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        q = ((m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s)
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        q = ((m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s)
    return tuple(float(v) for v in q)


def make_transform(rotation: np.ndarray, translation: tuple) -> np.ndarray:
    """4x4 homogeneous transform."""
    t = np.eye(4)
    t[:3, :3] = rotation
    t[:3, 3] = translation
    return t


def wrap_angle(a: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def mount_pose(entry: object, name: str) -> list:
    """[x, y, z, roll, pitch, yaw] of one entry of a mounts file ({parent, xyz, rpy}, URDF convention).

    Args:
        entry: the entry as read from the parameter server.
        name: its frame name, for error messages.

    Raises:
        ValueError: if xyz or rpy is missing, not 3 numbers, or not finite.
    """
    if not isinstance(entry, dict):
        raise ValueError("mount %s must be {parent, xyz, rpy}, got %r" % (name, entry))
    out = []
    for key in ("xyz", "rpy"):
        v = entry.get(key)
        if not isinstance(v, (list, tuple)) or len(v) != 3:
            raise ValueError("mount %s.%s must be 3 numbers, got %r" % (name, key, v))
        try:
            vals = [float(x) for x in v]
        except (TypeError, ValueError):
            raise ValueError("mount %s.%s must be 3 numbers, got %r" % (name, key, v)) from None
        if not all(math.isfinite(x) for x in vals):
            raise ValueError("mount %s.%s must be finite, got %r" % (name, key, v))
        out.extend(vals)
    return out

"""The one rotation module of RoboDog's Python: quaternions, roll/pitch/yaw and matrices.

Built on scipy's ``Rotation`` (Debian 11/12, Ubuntu 20.04; ``as_dcm``/``from_dcm`` are used where
scipy < 1.4 lacks ``as_matrix``/``from_matrix``). ROS-free; conventions are ROS's:

- quaternions are ``(x, y, z, w)`` tuples, or any object with ``x, y, z, w`` attributes
  (geometry_msgs/Quaternion), and are normalised before use;
- roll, pitch, yaw are fixed-axis rotations about x, then y, then z (URDF ``rpy``, tf's
  ``setRPY``): ``R = Rz(yaw) Ry(pitch) Rx(roll)``.
"""

import math
import warnings
from typing import Sequence, Tuple

import numpy as np
from scipy.spatial.transform import Rotation

Quaternion = Tuple[float, float, float, float]

_as_matrix = getattr(Rotation, "as_matrix", None) or Rotation.as_dcm
_from_matrix = getattr(Rotation, "from_matrix", None) or Rotation.from_dcm


def quat_tuple(q: object) -> Quaternion:
    """``(x, y, z, w)`` of a sequence or of an object with ``x, y, z, w`` attributes.

    Raises:
        ValueError: not four numbers, not finite, or of zero length.
    """
    if hasattr(q, "w"):
        vals = (q.x, q.y, q.z, q.w)
    else:
        vals = tuple(q)
    try:
        x, y, z, w = (float(v) for v in vals)
    except (TypeError, ValueError):
        raise ValueError("a quaternion is four numbers (x, y, z, w), got %r" % (q,)) from None
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(n) or n < 1e-9:
        raise ValueError("invalid quaternion %r" % (q,))
    return x, y, z, w


def _rotation(q: object) -> Rotation:
    return Rotation.from_quat(quat_tuple(q))


def _euler(r: Rotation) -> Tuple[float, float, float]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # gimbal lock: scipy sets roll to 0 and says so
        roll, pitch, yaw = r.as_euler("xyz")
    return float(roll), float(pitch), float(yaw)


def quat_to_rpy(q: object) -> Tuple[float, float, float]:
    """Roll, pitch, yaw [rad] of a quaternion (yaw and roll in [-pi, pi], pitch in [-pi/2, pi/2])."""
    return _euler(_rotation(q))


def yaw_of(q: object) -> float:
    """Yaw [rad] of a quaternion, e.g. ``yaw_of(msg.pose.pose.orientation)``."""
    return quat_to_rpy(q)[2]


def rpy_to_quat(roll: float, pitch: float, yaw: float) -> Quaternion:
    """Unit quaternion (x, y, z, w) of roll, pitch, yaw [rad]."""
    x, y, z, w = Rotation.from_euler("xyz", [roll, pitch, yaw]).as_quat()
    return float(x), float(y), float(z), float(w)


def yaw_to_quat(yaw: float) -> Quaternion:
    """Unit quaternion (x, y, z, w) of a rotation by ``yaw`` [rad] about z."""
    return rpy_to_quat(0.0, 0.0, yaw)


def quat_to_matrix(q: object) -> np.ndarray:
    """3x3 rotation matrix of a quaternion."""
    return np.asarray(_as_matrix(_rotation(q)), dtype=float)


def rpy_to_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """3x3 rotation matrix ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    return np.asarray(_as_matrix(Rotation.from_euler("xyz", [roll, pitch, yaw])), dtype=float)


def matrix_to_rpy(m: Sequence[Sequence[float]]) -> Tuple[float, float, float]:
    """Roll, pitch, yaw [rad] of a 3x3 rotation matrix (inverse of :func:`rpy_to_matrix`)."""
    return _euler(_from_matrix(np.asarray(m, dtype=float)))


def matrix_to_quat(m: Sequence[Sequence[float]]) -> Quaternion:
    """Unit quaternion (x, y, z, w) of a 3x3 rotation matrix."""
    x, y, z, w = _from_matrix(np.asarray(m, dtype=float)).as_quat()
    return float(x), float(y), float(z), float(w)


def wrap_angle(a: float) -> float:
    """Angle [rad] wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi

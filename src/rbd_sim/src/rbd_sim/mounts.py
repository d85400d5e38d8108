"""Pose of one entry of a mounts file (ROS-free); rotations live in :mod:`rbd_geometry.rotation`."""

import math


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

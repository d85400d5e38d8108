"""Sensor mounts from ``/tf_static`` without tf2 (ROS-free).

Melodic's ``tf2_py`` is built for Python 2 only, so the controller must not need ``tf2_ros``
to start. The mounts it needs never move: :class:`StaticFrames` keeps the latest static
transform of each child frame and chains them into a planar (x, y, yaw).
"""

import math
from typing import Dict, Optional, Sequence, Tuple

import numpy as np

from rbd_geometry.rotation import matrix_to_rpy, quat_to_matrix

__all__ = ["StaticFrames"]

Pose = Tuple[np.ndarray, np.ndarray]  # translation (3,) [m], rotation matrix (3, 3)
_MAX_DEPTH = 64  # a longer chain is a loop in the published tree


def _compose(a: Pose, b: Pose) -> Pose:
    """The pose b (given in a's frame) in a's parent frame."""
    return a[0] + a[1].dot(b[0]), a[1].dot(b[1])


def _inverse(a: Pose) -> Pose:
    rt = a[1].T
    return -rt.dot(a[0]), rt


class StaticFrames:
    """The static transform tree, fed from ``/tf_static`` messages."""

    def __init__(self) -> None:
        """An empty tree."""
        self._edges: Dict[str, Tuple[str, Pose]] = {}  # child -> (parent, pose in parent)

    def add(self, parent: str, child: str, translation: Sequence[float], rotation: Sequence[float]) -> None:
        """Set child's pose in parent (translation x, y, z [m]; rotation quaternion x, y, z, w).

        Raises:
            ValueError: A non-finite value or a zero quaternion.
        """
        values = [float(v) for v in translation] + [float(v) for v in rotation]
        if len(values) != 7 or not all(math.isfinite(v) for v in values):
            raise ValueError("transform %s -> %s: need 3 + 4 finite numbers" % (parent, child))
        try:
            rotation_matrix = quat_to_matrix(values[3:])
        except ValueError:
            raise ValueError("transform %s -> %s: zero quaternion" % (parent, child)) from None
        self._edges[child.lstrip("/")] = (parent.lstrip("/"), (np.array(values[:3]), rotation_matrix))

    def _to_root(self, frame: str) -> Tuple[str, Pose]:
        pose = (np.zeros(3), np.eye(3))
        for _ in range(_MAX_DEPTH):
            edge = self._edges.get(frame)
            if edge is None:
                return frame, pose
            frame, pose = edge[0], _compose(edge[1], pose)
        return "", pose  # a loop: connected to nothing

    def lookup(self, target: str, source: str) -> Optional[Tuple[float, float, float]]:
        """(x [m], y [m], yaw [rad]) of frame source in frame target; None while they are not connected."""
        root_s, in_root_s = self._to_root(source.lstrip("/"))
        root_t, in_root_t = self._to_root(target.lstrip("/"))
        if not root_s or root_s != root_t:
            return None
        t, r = _compose(_inverse(in_root_t), in_root_s)
        return float(t[0]), float(t[1]), matrix_to_rpy(r)[2]

"""Sensor mounts from ``/tf_static`` without tf2 (ROS-free).

Melodic's ``tf2_py`` is built for Python 2 only, so the controller must not need ``tf2_ros``
to start. The mounts it needs never move: :class:`StaticFrames` keeps the latest static
transform of each child frame and chains them into a planar (x, y, yaw).
"""

import math
from typing import Dict, Optional, Sequence, Tuple

from rbd_geometry.rotation import yaw_of

__all__ = ["StaticFrames"]

Vec = Tuple[float, float, float]
Quat = Tuple[float, float, float, float]  # x, y, z, w
_MAX_DEPTH = 64  # a longer chain is a loop in the published tree


def _qmul(a: Quat, b: Quat) -> Quat:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def _rotate(q: Quat, v: Vec) -> Vec:
    x, y, z, _ = _qmul(_qmul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)


def _compose(a: Tuple[Vec, Quat], b: Tuple[Vec, Quat]) -> Tuple[Vec, Quat]:
    """The pose b (given in a's frame) in a's parent frame."""
    r = _rotate(a[1], b[0])
    return (a[0][0] + r[0], a[0][1] + r[1], a[0][2] + r[2]), _qmul(a[1], b[1])


def _inverse(a: Tuple[Vec, Quat]) -> Tuple[Vec, Quat]:
    q = (-a[1][0], -a[1][1], -a[1][2], a[1][3])
    t = _rotate(q, a[0])
    return (-t[0], -t[1], -t[2]), q


class StaticFrames:
    """The static transform tree, fed from ``/tf_static`` messages."""

    def __init__(self) -> None:
        """An empty tree."""
        self._edges: Dict[str, Tuple[str, Tuple[Vec, Quat]]] = {}  # child -> (parent, pose in parent)

    def add(self, parent: str, child: str, translation: Sequence[float], rotation: Sequence[float]) -> None:
        """Set child's pose in parent (translation x, y, z [m]; rotation quaternion x, y, z, w).

        Raises:
            ValueError: A non-finite value or a zero quaternion.
        """
        values = [float(v) for v in translation] + [float(v) for v in rotation]
        if len(values) != 7 or not all(math.isfinite(v) for v in values):
            raise ValueError("transform %s -> %s: need 3 + 4 finite numbers" % (parent, child))
        norm = math.sqrt(sum(v * v for v in values[3:]))
        if norm < 1e-9:
            raise ValueError("transform %s -> %s: zero quaternion" % (parent, child))
        q = tuple(v / norm for v in values[3:])
        self._edges[child.lstrip("/")] = (parent.lstrip("/"), (tuple(values[:3]), q))

    def _to_root(self, frame: str) -> Tuple[str, Tuple[Vec, Quat]]:
        pose = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
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
        (x, y, _), q = _compose(_inverse(in_root_t), in_root_s)
        return x, y, yaw_of(q)

"""Message data to the avoidance's point arrays (numpy only; messages are duck-typed).

The node hands these the fields of sensor_msgs/PointCloud2, sensor_msgs/LaserScan and
nav_msgs/OccupancyGrid; tests hand them plain objects with the same fields.
"""

import math
from typing import Any, Optional, Sequence, Tuple

import numpy as np

from rbd_controller.blocking import is_low
from rbd_geometry.rotation import yaw_or_nan

FLOAT32 = 7  # sensor_msgs/PointField.FLOAT32


def cloud_xy(cloud: Any) -> np.ndarray:
    """The x, y of every point of a PointCloud2 with FLOAT32 x and y fields (N x 2, finite only).

    Raises:
        ValueError: no FLOAT32 x/y field, a big-endian cloud or a data size that does not match.
    """
    return cloud_columns(cloud, ("x", "y"))


def cloud_xyz(cloud: Any) -> np.ndarray:
    """The x, y, z of every point of a PointCloud2 with FLOAT32 x, y and z fields (N x 3, finite only).

    Raises:
        ValueError: no FLOAT32 x/y/z field, a big-endian cloud or a data size that does not match.
    """
    return cloud_columns(cloud, ("x", "y", "z"))


def blocking_points(cloud: Any, top_beam: Optional[float]) -> Tuple[np.ndarray, bool]:
    """rbd_lidar's collision_points: their x, y (N x 2, the cloud's frame) and whether they are a low obstacle.

    Low (:func:`rbd_controller.blocking.is_low`) needs the z field; a cloud without one is never low.

    Raises:
        ValueError: as :func:`cloud_columns`.
    """
    if not any(f.name == "z" for f in cloud.fields):
        return cloud_xy(cloud), False
    xyz = cloud_xyz(cloud)
    return xyz[:, :2], is_low(xyz, top_beam)


def cloud_columns(cloud: Any, names: Sequence[str]) -> np.ndarray:
    """The named FLOAT32 fields of every point of a PointCloud2 (N x len(names), rows with a non-finite value dropped).

    Raises:
        ValueError: a named field missing (or not one FLOAT32), a big-endian cloud or a data size that does not match.
    """
    offsets = {f.name: f.offset for f in cloud.fields if f.datatype == FLOAT32 and f.count == 1}
    if not all(n in offsets for n in names):
        raise ValueError("cloud has no FLOAT32 %s fields" % " and ".join(names))
    if cloud.is_bigendian:
        raise ValueError("big-endian clouds are not supported")
    n = int(cloud.width) * int(cloud.height)
    step = int(cloud.point_step)
    if n == 0:
        return np.zeros((0, len(names)))
    if step < 4 * len(names) or len(cloud.data) < n * step or int(cloud.row_step) * int(cloud.height) > len(cloud.data):
        raise ValueError("cloud data size does not match its layout")
    dtype = np.dtype({"names": list(names), "formats": ["<f4"] * len(names), "offsets": [offsets[k] for k in names],
                      "itemsize": step})
    rows = []
    buf = bytes(cloud.data) if not isinstance(cloud.data, (bytes, bytearray)) else cloud.data
    for r in range(int(cloud.height)):
        arr = np.frombuffer(buf, dtype=dtype, count=int(cloud.width), offset=r * int(cloud.row_step))
        rows.append(np.stack([arr[k] for k in names], axis=1).astype(np.float64))
    out = np.concatenate(rows)
    return out[np.all(np.isfinite(out), axis=1)]


def scan_xy(scan: Any, stride: int = 1) -> np.ndarray:
    """Points of a LaserScan within [range_min, range_max] in its frame (N x 2)."""
    ranges = np.asarray(scan.ranges, dtype=np.float64)[::stride]
    angles = scan.angle_min + scan.angle_increment * np.arange(len(scan.ranges))[::stride]
    ok = np.isfinite(ranges) & (ranges >= scan.range_min) & (ranges <= scan.range_max)
    return np.stack([ranges[ok] * np.cos(angles[ok]), ranges[ok] * np.sin(angles[ok])], axis=1)


def to_map(points: np.ndarray, mount: Tuple[float, float, float], pose: Tuple[float, float, float]) -> np.ndarray:
    """Sensor-frame points to the map frame.

    Through the sensor mount (x, y, yaw in base_link), then the robot pose (x, y, yaw in map).
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    out = pts
    for x, y, yaw in (mount, pose):
        c, s = math.cos(yaw), math.sin(yaw)
        out = np.stack([x + c * out[:, 0] - s * out[:, 1], y + s * out[:, 0] + c * out[:, 1]], axis=1)
    return out


def yaw_of(q: Any) -> float:
    """Heading of a quaternion (x, y, z, w fields) [rad]; NaN for a zero or non-finite one.

    NaN, not heading 0: the pose consumers drop non-finite poses (stale data stops the robot).
    """
    return yaw_or_nan(q)

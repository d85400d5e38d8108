"""A thin copy of an organised LiDAR cloud for a laptop on WLAN (no ROS; numpy only).

The full ouster-ros cloud is 48 bytes per point, 32 x 1024 points at 10 Hz (~126 Mbit/s): too
much for the robot's hotspot. The audience only needs the shape: every n-th column, only the
points with a return, and x, y, z plus one colour channel (16 bytes per point), at a lower rate.
"""

import math
from typing import Dict, Optional, Tuple

import numpy as np

#: sensor_msgs/PointField datatypes -> numpy little-endian types.
DATATYPES = {1: "i1", 2: "u1", 3: "<i2", 4: "<u2", 5: "<i4", 6: "<u4", 7: "<f4", 8: "<f8"}
#: Output layout: x, y, z FLOAT32 at 0/4/8, the channel at 12 (FLOAT32 or UINT32).
OUTPUT_POINT_STEP = 16


class CloudLayoutError(ValueError):
    """The input cloud cannot be thinned (missing fields, sizes that do not add up, ...)."""


def column_step(width: int, max_columns: int) -> int:
    """Every how many columns one is kept so that at most max_columns remain (>= 1)."""
    if width <= 0 or max_columns <= 0:
        raise ValueError("width and max_columns must be > 0")
    return max(1, int(math.ceil(width / float(max_columns))))


def thin_cloud(data: bytes, height: int, width: int, point_step: int, row_step: int,
               fields: Dict[str, Tuple[int, int]], channel: str, col_step: int,
               row_every: int = 1) -> Tuple[bytes, int, int]:
    """Keep every col_step-th column and every row_every-th row, drop points without a return.

    Args:
        data: the cloud's little-endian point data.
        height: rows of the cloud (PointCloud2 ``height``).
        width: columns (``width``).
        point_step: bytes per point.
        row_step: bytes per row.
        fields: field name -> (offset, PointField datatype); needs x, y, z (FLOAT32) and channel.
        channel: the field carried along for colouring (e.g. ``range`` or ``intensity``).
        col_step: keep every col_step-th column (>= 1).
        row_every: keep every row_every-th row (>= 1).

    Returns:
        (packed points, number of points, channel datatype): x y z float32 + channel (as float32,
        or uint32 for unsigned integer channels), 16 bytes per point.

    Raises:
        CloudLayoutError: if a field is missing or of the wrong type, or the sizes do not add up.
    """
    if col_step < 1 or row_every < 1:
        raise ValueError("col_step and row_every must be >= 1")
    for name in ("x", "y", "z"):
        if name not in fields or fields[name][1] != 7:
            raise CloudLayoutError("field %s missing or not FLOAT32" % name)
    if channel not in fields or fields[channel][1] not in DATATYPES:
        raise CloudLayoutError("channel field %r missing" % channel)
    if height < 1 or width < 1:
        raise CloudLayoutError("empty cloud (%d x %d)" % (height, width))
    for name, (offset, dtype) in fields.items():
        if name in ("x", "y", "z", channel) and offset + np.dtype(DATATYPES[dtype]).itemsize > point_step:
            raise CloudLayoutError("field %s at offset %d does not fit in point_step %d" % (name, offset, point_step))
    if row_step < width * point_step or len(data) < height * row_step:
        raise CloudLayoutError("data size %d does not match %d rows of %d bytes (width %d x point_step %d)"
                               % (len(data), height, row_step, width, point_step))
    raw = np.frombuffer(data, np.uint8, height * row_step).reshape(height, row_step)
    pts = raw[::row_every, : width * point_step].reshape(-1, width, point_step)[:, ::col_step, :]
    pts = pts.reshape(-1, point_step)

    def column(name: str) -> np.ndarray:
        offset, dtype = fields[name]
        size = np.dtype(DATATYPES[dtype]).itemsize
        return np.ascontiguousarray(pts[:, offset:offset + size]).view(DATATYPES[dtype]).ravel()

    x, y, z, c = column("x"), column("y"), column("z"), column(channel)
    valid = np.isfinite(x) & np.isfinite(y) & np.isfinite(z) & ~((x == 0) & (y == 0) & (z == 0))
    if channel == "range":
        valid &= c != 0
    out_kind = 6 if c.dtype.kind == "u" else 7
    out = np.empty(int(valid.sum()), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                            ("c", "<u4" if out_kind == 6 else "<f4")])
    out["x"], out["y"], out["z"], out["c"] = x[valid], y[valid], z[valid], c[valid]
    return out.tobytes(), len(out), out_kind


class Throttle:
    """Lets a message through at most rate times per second (by message stamps).

    A message is let through when at least 90 % of the period passed since the last one, so a
    10 Hz input with a little jitter gives 5 Hz at rate 5, not 3.3 Hz.
    """

    def __init__(self, rate: float) -> None:
        if not rate > 0.0:
            raise ValueError("rate must be > 0, got %r" % (rate,))
        self.period = 1.0 / rate
        self.last: Optional[float] = None

    def ready(self, stamp: float) -> bool:
        """Whether the message stamped ``stamp`` [s] goes out (and is counted as sent)."""
        if self.last is not None and 0.0 <= stamp - self.last < 0.9 * self.period:
            return False
        self.last = stamp
        return True

"""Synthetic ouster-ros clouds (point_type original, destaggered) for the rbd_lidar rostest.

Independent of the C++ code: the xyz follows the ouster-sdk xyzlut formula (INTERFACES.md) for
the OS1-32 U0 beam table; ranges are ray-cast against a floor, a square room and an optional
person-sized cylinder.
"""

import numpy as np
from sensor_msgs.msg import PointCloud2, PointField

ALTITUDE_DEG = [20.5477, 19.2919, 18.0171, 16.7242, 15.4141, 14.088, 12.7466, 11.3909, 10.022, 8.641, 7.249,
                5.8474, 4.4377, 3.0216, 1.601, 0.1779, -1.2454, -2.6668, -4.0842, -5.4956, -6.8994, -8.2939,
                -9.6778, -11.0499, -12.409, -13.754, -15.0841, -16.3982, -17.6955, -18.975, -20.2356, -21.4764]
AZIMUTH_DEG = -4.252
BEAM_ORIGIN = 0.015806
LIDAR_Z = 0.03618

OUSTER_DTYPE = np.dtype({
    "names": ["x", "y", "z", "intensity", "t", "reflectivity", "ring", "ambient", "range"],
    "formats": ["<f4", "<f4", "<f4", "<f4", "<u4", "<u2", "<u2", "<u2", "<u4"],
    "offsets": [0, 4, 8, 16, 20, 24, 26, 28, 32],
    "itemsize": 48,
})
FIELDS = [("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("intensity", 16, 7), ("t", 20, 6), ("reflectivity", 24, 4),
          ("ring", 26, 4), ("ambient", 28, 4), ("range", 32, 6)]


def rays(columns):
    """Unit rays and offsets (sensor frame) of every pixel, shapes (32, W, 3)."""
    phi = np.radians(np.array(ALTITUDE_DEG))[:, None]
    theta_e = 2.0 * np.pi * (1.0 - np.arange(columns) / float(columns))[None, :]
    theta_a = -np.radians(AZIMUTH_DEG)
    # os_lidar frame, then lidar_to_sensor: x -> -x, y -> -y, z + 36.18 mm.
    dl = np.stack(np.broadcast_arrays(np.cos(theta_e + theta_a) * np.cos(phi), np.sin(theta_e + theta_a) * np.cos(phi),
                                      np.sin(phi) + 0 * theta_e), axis=-1)
    ol = np.stack(np.broadcast_arrays(BEAM_ORIGIN * np.cos(theta_e) + 0 * phi, BEAM_ORIGIN * np.sin(theta_e) + 0 * phi,
                                      0 * phi + 0 * theta_e), axis=-1) - BEAM_ORIGIN * dl
    flip = np.array([-1.0, -1.0, 1.0])
    return dl * flip, ol * flip + np.array([0.0, 0.0, LIDAR_Z])


def pitch_matrix(pitch):
    """Rotation about y by `pitch` [rad] (ROS convention: positive = nose down)."""
    c, s = np.cos(pitch), np.sin(pitch)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def cast(columns, height=0.38, room=3.0, person=None, radius=0.2, pitch=0.0):
    """Range image [mm] (uint32, 32 x W) and sensor-frame xyz for a sensor `height` m above the floor.

    The sensor is pitched by `pitch` [rad]; the world (floor, walls, person) is level.
    """
    ds, os_ = rays(columns)
    rot = pitch_matrix(pitch)
    d, o = ds @ rot.T, os_ @ rot.T
    t = np.full(d.shape[:2], np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        floor = (-height - o[..., 2]) / d[..., 2]
        t = np.where((d[..., 2] < 0) & (floor > 0), np.minimum(t, floor), t)
        for axis in (0, 1):
            for wall in (room, -room):
                tw = (wall - o[..., axis]) / d[..., axis]
                t = np.where(tw > 0, np.minimum(t, tw), t)
        if person is not None:
            px, py = person
            a = d[..., 0] ** 2 + d[..., 1] ** 2
            bx, by = o[..., 0] - px, o[..., 1] - py
            b = 2 * (d[..., 0] * bx + d[..., 1] * by)
            c = bx ** 2 + by ** 2 - radius ** 2
            disc = b * b - 4 * a * c
            tc = (-b - np.sqrt(np.maximum(disc, 0))) / (2 * a)
            zc = o[..., 2] + tc * d[..., 2] + height
            hit = (disc >= 0) & (tc > 0) & (zc > 0) & (zc < 1.8)
            t = np.where(hit, np.minimum(t, tc), t)
    rng = np.where(np.isfinite(t), np.round(t * 1000.0), 0).astype(np.uint32)
    xyz = (rng[..., None] * 1e-3) * ds + os_
    xyz[rng == 0] = np.nan
    return rng, xyz


def make_cloud(stamp, columns=512, person=None, frame="os_sensor", pitch=0.0, height=0.38):
    """A valid ouster-ros PointCloud2 (32 x columns)."""
    rng, xyz = cast(columns, height=height, person=person, pitch=pitch)
    arr = np.zeros((32, columns), dtype=OUSTER_DTYPE)
    arr["x"], arr["y"], arr["z"] = xyz[..., 0], xyz[..., 1], xyz[..., 2]
    arr["range"] = rng
    arr["ring"] = np.arange(32)[:, None]
    msg = PointCloud2()
    msg.header.stamp = stamp
    msg.header.frame_id = frame
    msg.height, msg.width = 32, columns
    msg.fields = [PointField(name=n, offset=off, datatype=dt, count=1) for n, off, dt in FIELDS]
    msg.is_bigendian = False
    msg.point_step = 48
    msg.row_step = 48 * columns
    msg.is_dense = False
    msg.data = arr.tobytes()
    return msg


def malformed(stamp, kind, columns=512):
    """A broken cloud of the given kind."""
    msg = make_cloud(stamp, columns)
    if kind == "no_range":
        msg.fields = [f for f in msg.fields if f.name != "range"]
    elif kind == "point_step":
        msg.point_step = 32
    elif kind == "height":
        msg.height, msg.row_step = 16, msg.row_step * 2
    elif kind == "truncated":
        msg.data = msg.data[: len(msg.data) // 2]
    elif kind == "nan":
        arr = np.zeros((32, columns), dtype=OUSTER_DTYPE)
        arr["x"] = arr["y"] = arr["z"] = np.nan
        msg.data = arr.tobytes()
    elif kind == "empty":
        msg.height, msg.width, msg.row_step, msg.data = 0, 0, 0, b""
    else:
        raise ValueError(kind)
    return msg

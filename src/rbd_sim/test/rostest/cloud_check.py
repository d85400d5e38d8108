"""Helpers for the rbd_sim rostests: decode clouds independently, wait for fresh messages.

The layout is decoded here from the offsets of INTERFACES.md, not from rbd_sim.os1, so a
wrong layout in the simulator cannot make the tests agree with it.
"""

import json
import math
import os
import threading
import time

import numpy as np
import rospkg
import rospy

from rbd_testkit import wait_for

# ouster-ros "original" point: offsets per INTERFACES.md section 1.
DECODE = np.dtype(
    {
        "names": ["x", "y", "z", "pad", "intensity", "t", "reflectivity", "ring", "ambient", "range"],
        "formats": ["<f4", "<f4", "<f4", "<f4", "<f4", "<u4", "<u2", "<u2", "<u2", "<u4"],
        "offsets": [0, 4, 8, 12, 16, 20, 24, 26, 28, 32],
        "itemsize": 48,
    }
)


def metadata():
    path = os.path.join(rospkg.RosPack().get_path("rbd_sim"), "config", "os1-32-u0.json")
    with open(path) as f:
        return json.load(f)


def decode(msg):
    """(H, W) structured array of a PointCloud2 from os1_sim."""
    return np.frombuffer(bytes(msg.data), dtype=DECODE).reshape(msg.height, msg.width)


def beam_geometry(meta, width):
    """Per row altitude [rad], per (row, col) sensor-frame azimuth [rad], per col beam origin (x, y, z) [m]."""
    alt = np.radians(np.array(meta["beam_altitude_angles"]))
    az = np.radians(np.array(meta["beam_azimuth_angles"]))
    n = meta["lidar_origin_to_beam_origin_mm"] * 1e-3
    te = 2 * math.pi * (1 - np.arange(width) / float(width))
    # lidar_to_sensor is a 180 degree turn about z plus 36.18 mm up.
    lidar_angle = te[None, :] - az[:, None]
    sensor_az = np.arctan2(np.sin(lidar_angle + math.pi), np.cos(lidar_angle + math.pi))
    z_l = meta["lidar_to_sensor_transform"][11] * 1e-3
    origin = np.stack([-n * np.cos(te), -n * np.sin(te), np.full(width, z_l)], axis=-1)
    return alt, sensor_az, origin


class Latest:
    """Keeps messages of one topic; wait_new() returns the first one stamped after a time."""

    def __init__(self, topic, msg_type, keep=200):
        self.lock = threading.Lock()
        self.msgs = []
        self.keep = keep
        self.sub = rospy.Subscriber(topic, msg_type, self._cb, queue_size=50, buff_size=2**24)

    def _cb(self, msg):
        with self.lock:
            self.msgs.append((time.monotonic(), msg))
            del self.msgs[: -self.keep]

    def _first(self, keep, timeout, what):
        def found():
            with self.lock:
                return next((m for t, m in self.msgs if keep(t, m)), None)

        m = wait_for(found, timeout, 0.02, abort=rospy.is_shutdown)
        if m is None:
            raise AssertionError("no message on %s %s within %.0f s" % (self.sub.name, what, timeout))
        return m

    def wait_new(self, after, timeout=20.0):
        """First message stamped after ``after``."""
        return self._first(lambda _t, m: m.header.stamp > after, timeout, "after %s" % after.to_sec())

    def wait_received(self, timeout=20.0):
        """First message received after this call (for headerless types)."""
        start = time.monotonic()
        return self._first(lambda t, _m: t > start, timeout, "received")

    def window(self, seconds):
        time.sleep(seconds)
        with self.lock:
            now = time.monotonic()
            return [m for t, m in self.msgs if now - t <= seconds]

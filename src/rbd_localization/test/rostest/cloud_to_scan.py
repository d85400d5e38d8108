#!/usr/bin/env python3
"""Test helper: a horizontal slice of /ouster/points as a LaserScan on /scan (frame os_sensor).

Stands in for rbd_lidar's /scan when recording the regression bags (a cloud per scan would make
the bags hundreds of MB). Nearest return per 0.5 deg between ~z_min and ~z_max in os_sensor.
"""

import math

import numpy as np
import rospy
from sensor_msgs.msg import LaserScan, PointCloud2


class CloudToScan:
    """Subscribes the cloud, publishes the slice."""

    def __init__(self):
        self.bins = rospy.get_param("~bins", 720)
        self.z_min = rospy.get_param("~z_min", -0.07)
        self.z_max = rospy.get_param("~z_max", 0.33)
        self.pub = rospy.Publisher("/scan", LaserScan, queue_size=2)
        rospy.Subscriber("/ouster/points", PointCloud2, self.on_cloud, queue_size=1, buff_size=2 ** 24)

    def on_cloud(self, msg):
        offsets = {f.name: f.offset for f in msg.fields}
        if not all(k in offsets for k in ("x", "y", "z")):
            rospy.logwarn_throttle(5.0, "cloud_to_scan: cloud without x/y/z")
            return
        n = msg.width * msg.height
        raw = np.frombuffer(msg.data, dtype=np.uint8)[: n * msg.point_step].reshape(n, msg.point_step)
        xyz = [raw[:, offsets[k]:offsets[k] + 4].copy().view(np.float32).ravel() for k in ("x", "y", "z")]
        x, y, z = xyz
        ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(z) & (z >= self.z_min) & (z <= self.z_max)
        x, y = x[ok], y[ok]
        r = np.hypot(x, y)
        b = np.clip(((np.arctan2(y, x) + math.pi) / (2 * math.pi) * self.bins).astype(int), 0, self.bins - 1)
        ranges = np.full(self.bins, np.inf, dtype=np.float32)
        np.minimum.at(ranges, b, r.astype(np.float32))
        scan = LaserScan()
        scan.header = msg.header
        scan.angle_increment = 2 * math.pi / self.bins
        scan.angle_min = -math.pi + 0.5 * scan.angle_increment
        scan.angle_max = scan.angle_min + (self.bins - 1) * scan.angle_increment
        scan.range_min, scan.range_max = 0.3, 120.0
        scan.ranges = ranges.tolist()
        self.pub.publish(scan)


if __name__ == "__main__":
    rospy.init_node("cloud_to_scan")
    CloudToScan()
    rospy.spin()

#!/usr/bin/env python3
"""Where the simulated OS1 sits and where the LiDAR zone is, for one mounts file (ground truth).

Usage: mount_zone.py --mounts FILE --out JSON [--columns 512]

Starts the safety stack (`rbd_bringup sim.launch mounts:=FILE`, localization off) on a private
master and measures, with the robot standing where the simulator put it:

- `tf_mount`: TF base_link -> os_sensor (what the URDF says);
- `cloud_x`: where a flat target (1 m radius cylinder, surface 1.2 m ahead of the body in the
  world) shows up in the cloud, median x of its returns near y = 0 in os_sensor, as decoded by
  sensor_msgs.point_cloud2 (where the simulated sensor really is: 1.2 - body x - mount x);
- `front`, `back`: Fig. 23's bisection of the zone boundary (5 mm), measured from the body frame
  `collision_zone` (the zone's origin) with the target approaching along the body's x axis.
"""

import argparse
import json
import math
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import experiments  # noqa: E402

from rbd_testkit import RosEnv, free_port  # noqa: E402

TARGET_RADIUS = 1.0
TARGET_SURFACE_X = 1.2


def cloud_target_x(since):
    """Median x (os_sensor) of the returns near y = 0, z = 0 ahead (the target's surface).

    From the first cloud stamped after ``since`` (the target's placement) that has the target in
    it: a scan under way at the placement may have swept y = 0 before the target was there.
    """
    import rospy
    from sensor_msgs import point_cloud2
    from sensor_msgs.msg import PointCloud2

    xs = []
    for _ in range(50):
        cloud = rospy.wait_for_message("/ouster/points", PointCloud2, timeout=5.0)
        if cloud.header.stamp <= since:
            continue
        xs = [x for x, y, z in point_cloud2.read_points(cloud, ("x", "y", "z"), skip_nans=True)
              if x > 0.5 and abs(y) < 0.03 and abs(z) < 0.1]
        if len(xs) >= 3:
            return statistics.median(xs), len(xs)
    raise RuntimeError("target not in the cloud (%d returns)" % len(xs))


def measure(mounts):
    """The measurements above on the running stack (a ROS node of this process already), as a dict.

    Args:
        mounts: the mounts file the stack was started with (recorded in the result).

    The robot must stand where the simulator put it (facing +x): first on a stack.
    """
    import rospy
    import tf2_ros

    result = {"mounts": os.path.abspath(mounts)}
    truth = experiments.Truth()
    if not experiments.wait_for(lambda: truth.last() is not None, 60.0):
        raise RuntimeError("no ground truth")
    zone = experiments.Zone("collision_zone")
    buf = tf2_ros.Buffer()
    tf2_ros.TransformListener(buf)
    t = buf.lookup_transform("base_link", "os_sensor", rospy.Time(0), rospy.Duration(30.0)).transform.translation
    result["tf_mount"] = [t.x, t.y, t.z]
    _, body_x, body_y = truth.last()[:3]
    result["truth_xy"] = [body_x, body_y]
    # The flat target straight ahead of the body (the robot faces +x at start).
    placed = rospy.Time.now()
    place = zone.place(name="flat", x=body_x + TARGET_SURFACE_X + TARGET_RADIUS, y=body_y, radius=TARGET_RADIUS,
                       height=1.7, remove=False)
    if not place.success:
        raise RuntimeError("place_obstacle refused")
    result["cloud_x"], result["cloud_returns"] = cloud_target_x(placed)
    zone.remove("flat")
    for side, angle, target in (("front", 0.0, zone.zone[0]), ("back", math.pi, zone.zone[1])):
        flip = experiments.flip_distance(zone, "fig23", angle, TARGET_RADIUS, target + TARGET_RADIUS, 0.005)
        result[side] = None if flip is None else flip - TARGET_RADIUS
        result[side + "_set"] = target
        zone.remove("fig23")
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mounts", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--columns", type=int, default=512)
    args = ap.parse_args()
    log_dir = os.path.join(os.path.dirname(os.path.abspath(args.out)), "logs-" + os.path.basename(args.out))
    stack = RosEnv(log_dir=log_dir, use_here=True, prefix="rbd-exp-home.")
    try:
        stack.launch("rbd_bringup", "sim.launch", "localization:=false", "rviz:=false", "gui:=false",
                     "seed:=1", "lidar_columns:=%d" % args.columns, "bridge_port:=%d" % free_port(),
                     "mounts:=" + os.path.abspath(args.mounts), name="sim")
        import rospy

        rospy.init_node("mount_zone", anonymous=True, disable_signals=True)
        result = measure(args.mounts)
    finally:
        stack.close(timeout=25.0)  # roslaunch itself escalates SIGINT -> SIGTERM after 15 s
    with open(args.out, "w") as fh:
        json.dump(result, fh, indent=2, sort_keys=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

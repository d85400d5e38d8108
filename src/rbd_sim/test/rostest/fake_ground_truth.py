#!/usr/bin/env python3
"""Test helper: publishes a fixed synthetic /rbd_sim/ground_truth (stands in for mock_a1)."""

import rospy
from nav_msgs.msg import Odometry

from rbd_geometry.rotation import rpy_to_quat


def main():
    rospy.init_node("fake_ground_truth")
    pose = [float(v) for v in rospy.get_param("~pose", [0.0, 0.0, 0.28, 0.0, 0.0, 0.0])]
    pub = rospy.Publisher("/rbd_sim/ground_truth", Odometry, queue_size=10)
    rate = rospy.Rate(float(rospy.get_param("~rate", 100.0)))
    msg = Odometry()
    msg.header.frame_id = "world"
    msg.child_frame_id = "base_link_gt"
    msg.pose.pose.position.x, msg.pose.pose.position.y, msg.pose.pose.position.z = pose[:3]
    q = rpy_to_quat(*pose[3:])
    o = msg.pose.pose.orientation
    o.x, o.y, o.z, o.w = q
    while not rospy.is_shutdown():
        msg.header.stamp = rospy.Time.now()
        pub.publish(msg)
        try:
            rate.sleep()
        except rospy.ROSInterruptException:
            break


if __name__ == "__main__":
    main()

"""rbd_controller takes its LiDAR mount from /tf_static without tf2_ros (issue 28).

A private master with the controller and ``static_tf`` (base_link -> os1: 0.1 m ahead, turned
90 deg left). A probe (its own process: a pytest process may be a ROS node only once) gives the
controller a pose (2, 3, heading 0) and blocking points at (1, 0) in ``os1``, and prints where
the controller's /rbd_controller/blocking_points marker puts them in the map: (2.1, 4.0) only if
the mount was read and composed.
"""

import sys

PROBE = r"""
import rospy
import struct
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import PointCloud2, PointField
from visualization_msgs.msg import Marker

from rbd_testkit import wait_for

rospy.init_node("mount_probe")
seen = []
rospy.Subscriber("/rbd_controller/blocking_points", Marker, lambda m: seen.append(m))
pose_pub = rospy.Publisher("/pose", PoseStamped, queue_size=1)
cloud_pub = rospy.Publisher("/rbd_lidar/collision_points", PointCloud2, queue_size=1)
pose = PoseStamped()
pose.header.frame_id = "map"
pose.pose.position.x, pose.pose.position.y, pose.pose.orientation.w = 2.0, 3.0, 1.0
cloud = PointCloud2()
cloud.header.frame_id = "os1"
cloud.height, cloud.width, cloud.point_step, cloud.row_step = 1, 1, 12, 12
cloud.fields = [PointField(n, 4 * i, PointField.FLOAT32, 1) for i, n in enumerate("xyz")]
cloud.data = struct.pack("<3f", 1.0, 0.0, 0.0)


def give(_event):
    pose.header.stamp = cloud.header.stamp = rospy.Time.now()
    pose_pub.publish(pose)
    cloud_pub.publish(cloud)


sensor = rospy.Timer(rospy.Duration(0.1), give)  # a 10 Hz pose and LiDAR, until the marker comes
wait_for(lambda: seen, 60.0, abort=rospy.is_shutdown)
sensor.shutdown()
if seen:
    p = seen[-1].points[0]
    print("point %.3f %.3f" % (p.x, p.y), flush=True)
else:
    print("no blocking_points within 60 s", flush=True)
"""


def test_blocking_points_are_placed_through_the_static_mount(ros_env):
    ros_env.start(["rosrun", "rbd_description", "static_tf", "0.1", "0", "0.2", "1.5707963", "0", "0",
                   "base_link", "os1"],
                  name="static_tf")
    controller = ros_env.start(["rosrun", "rbd_controller", "rbd_controller"], name="rbd_controller")
    probe = ros_env.start([sys.executable, "-c", PROBE], name="probe", capture=True)
    lines = [line.strip() for line in probe.stdout]
    assert lines and lines[-1].startswith("point "), (lines, ros_env.output(controller)[-3000:])
    x, y = (float(v) for v in lines[-1].split()[1:])
    assert abs(x - 2.1) < 1e-3 and abs(y - 4.0) < 1e-3, lines

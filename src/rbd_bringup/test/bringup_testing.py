"""Helpers of rbd_bringup's launch tests: stand-in driver packages (the private master: rbd_testkit).

Neither ouster-ros nor zed-ros-wrapper is in Debian. The stand-ins are catkin packages named
``ouster_ros`` and ``zed_wrapper`` in a temporary directory put first on ROS_PACKAGE_PATH. Their
launch files declare the arguments of the real ones (names and defaults copied from
ouster-lidar/ouster-ros@c39f875 ``launch/sensor.launch`` and stereolabs/zed-ros-wrapper@3075f62
``zed_wrapper/launch/zed2.launch``; roslaunch refuses an argument a file does not declare) and
only record the value of each as a parameter ``/standin/<package>/<file>/<arg>``. The ZED stand-in
keeps the wrapper's structure where our launch file depends on it: node ``<camera_name>/<node_name>``
loading ``params/common.yaml`` (pos_tracking publish_tf / publish_map_tf true, as the wrapper's),
and a ``<camera_name>_description`` URDF parameter while ``publish_urdf`` is true.
"""

import os
import stat

HERE = os.path.dirname(os.path.abspath(__file__))

#: ouster-ros sensor.launch (master, c39f875): argument -> default (None: required).
OUSTER_SENSOR_ARGS = [
    ("ouster_ns", "ouster"), ("sensor_hostname", None), ("udp_dest", " "), ("lidar_port", "0"), ("imu_port", "0"),
    ("udp_profile_lidar", " "), ("lidar_mode", " "), ("timestamp_mode", " "), ("ptp_utc_tai_offset", "-37.0"),
    ("metadata", " "), ("viz", "true"), ("rviz_config", "$(find ouster_ros)/config/viz.rviz"), ("tf_prefix", " "),
    ("sensor_frame", "os_sensor"), ("lidar_frame", "os_lidar"), ("imu_frame", "os_imu"), ("point_cloud_frame", " "),
    ("pub_static_tf", "true"), ("no_bond", "false"), ("dynamic_transforms_broadcast", "false"),
    ("dynamic_transforms_broadcast_rate", "1.0"), ("proc_mask", "IMG|PCL|IMU|SCAN|TLM"), ("scan_ring", "0"),
    ("point_type", "original"), ("azimuth_window_start", "0"), ("azimuth_window_end", "360000"),
    ("persist_config", "false"), ("attempt_reconnect", "false"), ("dormant_period_between_reconnects", "1.0"),
    ("max_failed_reconnect_attempts", "2147483647"), ("organized", "true"), ("destagger", "true"),
    ("min_range", "0.0"), ("max_range", "10000.0"), ("min_scan_valid_columns_ratio", "0.0"), ("v_reduction", "1"),
]
#: zed-ros-wrapper zed2.launch (3075f62): argument -> default.
ZED2_ARGS = [
    ("svo_file", ""), ("stream", ""), ("node_name", "zed_node"), ("camera_model", "zed2"), ("publish_urdf", "true"),
    ("camera_name", "zed2"), ("base_frame", "base_link"), ("cam_pos_x", "0.0"), ("cam_pos_y", "0.0"),
    ("cam_pos_z", "0.0"), ("cam_roll", "0.0"), ("cam_pitch", "0.0"), ("cam_yaw", "0.0"),
]
#: The wrapper's params/common.yaml, the part our launch file overrides (0225df0).
ZED_COMMON_YAML = """pos_tracking:
    pos_tracking_enabled:       true
    publish_tf:                 true
    publish_map_tf:             true
    map_frame:                  'map'
    odometry_frame:             'odom'
general:
    camera_name:                zed
    base_frame:                 'base_link'
"""


def _package(root, name):
    os.makedirs(os.path.join(root, name, "launch"))
    with open(os.path.join(root, name, "package.xml"), "w") as fh:
        fh.write('<?xml version="1.0"?>\n<package format="2"><name>%s</name><version>0.0.0</version>'
                 "<description>RoboDog test stand-in: records the launch arguments it is given</description>"
                 '<maintainer email="robodog@example.org">RoboDog</maintainer><license>BSD</license>'
                 "<buildtool_depend>catkin</buildtool_depend></package>\n" % name)


def _recording_args(args, package, launch):
    lines = []
    for name, default in args:
        lines.append('  <arg name="%s"%s/>' % (name, "" if default is None else ' default="%s"' % default))
    for name, _ in args:
        lines.append('  <param name="/standin/%s/%s/%s" type="str" value="$(arg %s)"/>' % (package, launch, name, name))
    return "\n".join(lines)


def make_standins(root):
    """Write the stand-in ouster_ros and zed_wrapper packages under root; returns root."""
    _package(root, "ouster_ros")
    with open(os.path.join(root, "ouster_ros", "launch", "sensor.launch"), "w") as fh:
        fh.write("<launch>\n%s\n</launch>\n" % _recording_args(OUSTER_SENSOR_ARGS, "ouster_ros", "sensor"))
    _package(root, "zed_wrapper")
    os.makedirs(os.path.join(root, "zed_wrapper", "params"))
    with open(os.path.join(root, "zed_wrapper", "params", "common.yaml"), "w") as fh:
        fh.write(ZED_COMMON_YAML)
    node = os.path.join(root, "zed_wrapper", "zed_wrapper_node")
    with open(node, "w") as fh:
        fh.write("#!/usr/bin/env python3\n# Stand-in for the ZED wrapper node: exists, does nothing.\n"
                 "import rospy\nrospy.init_node('zed_node')\nrospy.spin()\n")
    os.chmod(node, os.stat(node).st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    with open(os.path.join(root, "zed_wrapper", "launch", "zed2.launch"), "w") as fh:
        fh.write("""<launch>
%s
  <group ns="$(arg camera_name)">
    <group if="$(arg publish_urdf)">
      <param name="$(arg camera_name)_description" value="stand-in of the wrapper's zed_descr.urdf.xacro"/>
    </group>
    <node name="$(arg node_name)" pkg="zed_wrapper" type="zed_wrapper_node" output="screen">
      <rosparam file="$(find zed_wrapper)/params/common.yaml" command="load"/>
      <param name="general/camera_name" value="$(arg camera_name)"/>
      <param name="general/base_frame" value="$(arg base_frame)"/>
    </node>
  </group>
</launch>
""" % _recording_args(ZED2_ARGS, "zed_wrapper", "zed2"))
    return root

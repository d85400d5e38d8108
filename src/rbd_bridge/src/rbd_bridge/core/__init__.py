"""The ROS-free core of rbd_bridge (a test imports it with rospy, genpy and roslib blocked)."""

"""The ROS edge of rbd_bridge: topics, services, rosapi adapters, message mapping (rospy, genpy)."""

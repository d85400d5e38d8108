"""RoboDog's robot model: the A1 URDF from the sensor mounts file, the standing-pose fallback (ROS-free)."""

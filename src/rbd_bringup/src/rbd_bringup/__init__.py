"""RoboDog system bringup: the audience's thinned cloud, recording, the demo's metrics and report (ROS-free)."""

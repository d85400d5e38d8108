"""ROS side of gesture recognition: gesture topic in, GetLastGesture service."""

"""RoboDog's geometry helpers (ROS-free): see :mod:`rbd_geometry.rotation`."""

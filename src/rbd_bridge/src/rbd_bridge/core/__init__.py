"""The ROS-free core of rbd_bridge: protocol, encodings, allow-lists, flow control, transport.

Nothing here imports rospy, genpy or roslib (a test imports every module with them
blocked); the ROS side lives in :mod:`rbd_bridge.ros` and is handed in as a backend.
"""

"""qre_ros-style Unitree A1 driver: cmd_vel and set_body_pose to high-level LCM, state to odometry/IMU."""

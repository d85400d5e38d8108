"""Mock A1 (LCM peer of the driver), simulated OS1-32, ZED2 and IMU, world with people."""

"""RoboDog system bringup: launch files, RViz configs, robot model and system-level metrics."""

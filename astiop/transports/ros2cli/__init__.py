"""ROS 2 through the `ros2` executable: one process per command, long-lived echo streams."""

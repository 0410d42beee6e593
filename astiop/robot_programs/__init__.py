"""The simulator served as a robot in a process of its own: behind an emulated `ros2` CLI
(`emulated_cli`), or as real ROS 2 nodes over DDS (`ros2_node`)."""

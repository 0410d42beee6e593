"""The simulator served as a robot in a process of its own: behind an emulated `ros2` CLI."""

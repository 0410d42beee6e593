"""The robot backends, one subpackage each: sim (in process), ros2cli (the `ros2` executable),
replay (a recording, read-only)."""

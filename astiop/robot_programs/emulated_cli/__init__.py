"""An emulated ROS 2 robot in its own process, and the `ros2` executable that talks to it."""

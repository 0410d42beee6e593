"""The robot transports: how a command reaches a robot (the simulator in process, rclpy,
the `ros2` executable, a recording), and the contract each one keeps (base.py)."""

"""The one door to the robot: the gateway (review, run, drive, the E-STOP), safety, the live
state, what is in flight, the factory, and the backends (sim, rclpy, the ros2 CLI, replay)."""

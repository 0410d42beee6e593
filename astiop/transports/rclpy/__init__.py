"""ROS 2 in process through rclpy (the robot's own install, or the astiop[ros] wheels): one
context per process, state by subscription, every command executed natively."""

"""The simulator as real ROS 2 nodes (`astiop sim node`): a robot the real ros2 CLI, rviz,
Foxglove and astiop's ROS 2 backends read and drive over DDS."""

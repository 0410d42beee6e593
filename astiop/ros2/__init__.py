"""The ROS 2 vocabulary, pure: message/service/action definitions, the catalog, ros2cli's grammar
per distro, validation, rendering and printing as ros2cli prints. Imports nothing of the robot,
the store, the simulator, the agent, the bench, the recordings or the UI."""

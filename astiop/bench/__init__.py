"""The two-stage benchmark of the paper: ROS knowledge, then robot commands on the simulator."""

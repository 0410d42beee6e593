"""A TurtleBot3 (Burger or Waffle) under Nav2, as real ROS 2 nodes in the simulated warehouse
(`astiop sim node --robot turtlebot3`): a robot astiop did not write, with the names, types and
units upstream gives it, to test astiop against. Its parameters and robot description are a
table of our own with upstream's values (params.py cites the files)."""

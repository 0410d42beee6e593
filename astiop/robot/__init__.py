"""The ROS 2-shaped robot graph: types, catalog, grammar, validation, safety, backends."""

"""The ASTIbot warehouse simulator: kinematics, physics, lidar, battery, navigation."""

"""The simulator in process: the default robot."""

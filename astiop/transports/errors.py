"""The robot layer's error: a valid command whose running failed (raised by the verbs too)."""

from astiop.ros2.verbs.base import BackendError  # noqa: F401 - its home for the transports

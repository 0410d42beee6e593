"""Whether rclpy and the robot's message packages import here (no import of rclpy otherwise)."""

from __future__ import annotations

import importlib

# the packages of the types the catalog names
MESSAGE_PACKAGES = (
    "geometry_msgs.msg", "sensor_msgs.msg", "nav_msgs.msg", "std_srvs.srv", "diagnostic_msgs.msg",
    "rcl_interfaces.srv", "astiop_msgs.msg", "nav2_msgs.action", "tf2_msgs.msg",
)  # fmt: skip


def rclpy_missing() -> str:
    """Why the rclpy transport cannot run here, in a few words; "" when it can."""
    try:
        importlib.import_module("rclpy")
    except ImportError:
        return "rclpy not importable"
    except Exception as exc:  # noqa: BLE001 - a broken install (missing .so) is said, not raised
        return f"rclpy does not load ({type(exc).__name__}: {exc})"
    for module in MESSAGE_PACKAGES:
        try:
            importlib.import_module(module)
        except ImportError:
            package = module.split(".")[0]
            hint = (
                " (astiop ros2 build-interfaces)"
                if package in ("astiop_msgs", "nav2_msgs", "tf2_msgs")
                else ""
            )
            return f"{package} not importable{hint}"
    return ""

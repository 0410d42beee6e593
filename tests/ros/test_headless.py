"""The core never imports textual: the CLI, tests and bench drive it without a terminal. Nor does
it need the [ros] extra, which cannot install everywhere (a Jetson, an aarch64 laptop, a Mac)."""

import pkgutil
import subprocess
import sys

import astiop
from tests.ros import require_ros

UI = ("astiop.app", "astiop.screens", "astiop.widgets", "astiop.cli.console")

# Modules that import rclpy (the [ros] extra): imported only where it is installed, and skipped
# with the reason elsewhere. `available` says whether rclpy imports, so it must not need it.
ROS = (
    "astiop.transports.rclpy.",
    "astiop.robot_programs.ros2_node.node",
    "astiop.robot_programs.ros2_node.fleet",
    "astiop.robot_programs.ros2_common",
    "astiop.robot_programs.turtlebot3.node",
    "astiop.robot_programs.turtlebot3.navigator",
    "astiop.robot_programs.emulated_cli.dds",  # the emulated ros2 over DDS: dds, dds_calls, ...
)
ROS_FREE = ("astiop.transports.rclpy.available",)

# In the child, the [ros] extra's modules refuse to import, as where it is not installed: the
# client library and every interface package (what a ROS module needs first).
WITHOUT_ROS = """
import importlib.abc, sys
class WithoutRos(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        top = name.split(".")[0]
        if top == "rclpy" or top.startswith("rosidl") or top.endswith(("_msgs", "_srvs")):
            raise ModuleNotFoundError(f"No module named {name!r} (the [ros] extra is absent)")
sys.meta_path.insert(0, WithoutRos())
"""


def needs_ros(name: str) -> bool:
    return name.startswith(ROS) and name not in ROS_FREE


def headless_modules() -> list[str]:
    names = [m.name for m in pkgutil.walk_packages(astiop.__path__, "astiop.")]
    return sorted(n for n in names if not n.startswith(UI) and n != "astiop.__main__")


def textual_imported_by(modules: list[str], prelude: str = "") -> str:
    """The textual modules that importing `modules` in a fresh interpreter brings in."""
    code = prelude + (
        "import importlib, sys\n"
        f"for m in {modules!r}:\n"
        "    importlib.import_module(m)\n"
        "bad = sorted(m for m in sys.modules if m == 'textual' or m.startswith('textual.'))\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, f"the core does not import:\n{out.stderr}"
    return out.stdout.strip()


def test_core_does_not_import_textual_nor_need_ros():
    modules = [n for n in headless_modules() if not needs_ros(n)]
    assert "astiop.sim.simulator" in modules and "astiop.store" in modules
    assert "astiop.robot.factory" in modules and "astiop.robot_programs.ros2_node.run" in modules
    assert "astiop.robot_programs.turtlebot3.run" in modules
    bad = textual_imported_by(modules, prelude=WITHOUT_ROS)
    assert bad == "", f"textual imported by the core: {bad}"


def test_ros_modules_do_not_import_textual():
    require_ros()  # skipped without the [ros] extra (failed in CI's run with it)
    modules = [n for n in headless_modules() if needs_ros(n)]
    assert "astiop.transports.rclpy.backend" in modules
    assert "astiop.robot_programs.ros2_node.node" in modules
    bad = textual_imported_by(modules)
    assert bad == "", f"textual imported by the ROS modules: {bad}"

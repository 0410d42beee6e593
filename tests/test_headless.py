"""The core never imports textual: the CLI, tests and bench drive it without a terminal."""

import importlib.util
import pkgutil
import subprocess
import sys

import astiop

UI = ("astiop.app", "astiop.screens", "astiop.widgets", "astiop.cli.console")


# Modules that import rclpy: checked where ROS 2 is installed (CI installs it)
ROS = ("astiop.sim_robots.ros2_node.node",)


def core_modules() -> list[str]:
    names = [m.name for m in pkgutil.walk_packages(astiop.__path__, "astiop.")]
    skip = UI + (() if importlib.util.find_spec("rclpy") else ROS)
    return sorted(n for n in names if not n.startswith(skip) and n != "astiop.__main__")


def test_core_does_not_import_textual():
    modules = core_modules()
    assert "astiop.sim.simulator" in modules and "astiop.store" in modules
    code = (
        "import importlib, sys\n"
        f"for m in {modules!r}:\n"
        "    importlib.import_module(m)\n"
        "bad = sorted(m for m in sys.modules if m == 'textual' or m.startswith('textual.'))\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"textual imported by the core: {out.stdout}"

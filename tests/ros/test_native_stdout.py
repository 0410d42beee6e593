"""A process that started rclpy prints only its own data on stdout: what the middleware writes
there itself (Fast DDS's "[RTPS_TRANSPORT_SHM Error] Failed init_port ...", seen in CI before a
`robot profile --json`) goes to stderr."""

from __future__ import annotations

import json
import subprocess
import sys

from tests.ros import require_ros

_NATIVE = """
import ctypes, json
{start}
line = b"[RTPS_TRANSPORT_SHM Error] Failed init_port fastrtps_port7008\\n"
ctypes.CDLL(None).write(1, line, len(line))  # as the middleware writes: from C, to descriptor 1
print(json.dumps({{"name": "turtlebot3"}}))
"""


def _run(start: str) -> subprocess.CompletedProcess:
    code = _NATIVE.format(start=start)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)


def test_the_middleware_s_own_lines_go_to_stderr_once_rclpy_started():
    require_ros()
    out = _run("from astiop.transports.rclpy.node import ros_process\nros_process()")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout) == {"name": "turtlebot3"}
    assert "Failed init_port" in out.stderr


def test_a_served_console_s_stream_to_its_tab_carries_no_native_line():
    """The web driver writes its frames to `sys.__stdout__.fileno()`: once moved, they reach
    the tab and the middleware's line goes to stderr."""
    start = (
        "import os, sys\n"
        "from astiop.native_stdout import native_output_to_stderr\n"
        "native_output_to_stderr()\n"
        "os.write(sys.__stdout__.fileno(), b'D\\x00\\x00\\x00\\x02hi')"
    )
    out = _run(start)
    assert out.returncode == 0, out.stderr
    assert out.stdout == 'D\x00\x00\x00\x02hi{"name": "turtlebot3"}\n'
    assert "Failed init_port" in out.stderr

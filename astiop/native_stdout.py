"""Keep this process's stdout for what astiop prints.

Native libraries loaded with rclpy write their own diagnostics to file descriptor 1: Fast DDS
prints "[RTPS_TRANSPORT_SHM Error] Failed init_port ..." there when a shared-memory lock is
stale. On a `--json` command or an emulated `ros2 topic echo`, that line lands in the data a
program parses. Before rclpy starts, descriptor 1 is pointed at stderr, and Python's stdout
keeps a copy of the original, so only Python's own prints reach it.
"""

from __future__ import annotations

import io
import os
import sys

_moved = False


def stdout_is_the_screen() -> None:
    """A console's descriptor 1 is its screen (or `astiop serve`'s web driver): left alone."""
    global _moved
    _moved = True


def native_output_to_stderr() -> None:
    """Send native writes to descriptor 1 to stderr; leave `sys.stdout` where it was. Done at
    most once, and only when `sys.stdout` is descriptor 1 itself (not a capture, not a
    terminal app's redirection)."""
    global _moved
    if _moved:
        return
    try:
        if sys.stdout is None or sys.stdout.fileno() != 1:
            return
        sys.stdout.flush()
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        return
    kept = os.dup(1)
    os.set_inheritable(kept, False)
    stream = sys.stdout
    sys.stdout = io.TextIOWrapper(
        open(kept, "wb", closefd=True),  # noqa: SIM115 - lives as long as the process
        encoding=getattr(stream, "encoding", None) or "utf-8",
        errors=getattr(stream, "errors", None) or "strict",
        line_buffering=getattr(stream, "line_buffering", False),
    )
    os.dup2(2, 1)
    _moved = True

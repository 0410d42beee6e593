"""Keep this process's stdout for what astiop writes there.

Native libraries loaded with rclpy write their own diagnostics to file descriptor 1: Fast DDS
prints "[RTPS_TRANSPORT_SHM Error] Failed init_port ..." there when a shared-memory lock is
stale. On a `--json` command that line lands in the data a program parses; in a console served
by `astiop serve` it lands in the web driver's framed stream to the browser's tab. Before rclpy
starts, descriptor 1 is pointed at stderr, and `sys.stdout` (and `sys.__stdout__`, where the web
driver and the terminal queries write) becomes a stream on a copy of the original: Python's own
writes reach it, the native ones go to stderr.
"""

from __future__ import annotations

import io
import os
import sys

_done = False


def native_output_to_stderr() -> None:
    """Done once per process, before rclpy starts, and only when `sys.stdout` is descriptor 1
    itself (not a test's capture, not an app's redirection). A stream that kept the old
    `sys.stdout` before this writes to stderr from now on: call it early."""
    global _done
    if _done:
        return
    _done = True
    stream = sys.stdout
    try:
        if stream is None or stream.fileno() != 1:
            return
        stream.flush()
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        return
    kept = os.dup(1)  # not inherited by child processes (os.dup's default)
    moved = io.TextIOWrapper(
        open(kept, "wb", closefd=True),  # noqa: SIM115 - lives as long as the process
        encoding=getattr(stream, "encoding", None) or "utf-8",
        errors=getattr(stream, "errors", None) or "strict",
        line_buffering=getattr(stream, "line_buffering", False),
        write_through=getattr(stream, "write_through", False),
    )
    sys.stdout = moved
    if sys.__stdout__ is stream:
        sys.__stdout__ = moved  # type: ignore[misc]  # Final in typeshed; settable at run time
    os.dup2(2, 1)

"""The store's liveness check: whether the process that left a row `running` is still there.
Used on open to mark turns (store/__init__.py) and missions (store/missions.py) interrupted."""

from __future__ import annotations

import os


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    try:  # a zombie (killed, its parent not yet told) is gone all the same
        with open(f"/proc/{pid}/stat", "rb") as stat:
            return stat.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except (OSError, IndexError):
        return True

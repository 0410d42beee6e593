"""Starting the embedded model's process (`model_process`), possibly ahead of need.

`astiop chat` starts one first thing, before its own imports (~0.3 s of them): the child's Python
and xllamacpp load meanwhile, then it waits for its settings on stdin. `spawn()` hands that
process over when the model is wanted. Unused, it is killed (`discard_ahead`), or it ends when
its stdin closes, with this process, however that ends. Only the standard library here: it is
imported before anything else.
"""

from __future__ import annotations

import contextlib
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).with_name("model_process.py")
_ahead: subprocess.Popen | None = None


def _popen() -> subprocess.Popen:
    # -I: nothing from the environment or the working folder shadows what it imports
    return subprocess.Popen(
        [sys.executable, "-I", str(SCRIPT)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,  # a crash is reported by its exit code
        start_new_session=True,  # Ctrl-C reaches this process, which stops the model
    )


def start_ahead() -> None:
    """A model process started now, for a command that will likely serve the embedded model."""
    global _ahead
    if _ahead is None:
        with contextlib.suppress(OSError):
            _ahead = _popen()


def spawn() -> subprocess.Popen:
    """The process started ahead if it still runs, else a new one (OSError if none starts)."""
    global _ahead
    proc, _ahead = _ahead, None
    if proc is not None and proc.poll() is None:
        return proc
    if proc is not None:
        close_pipes(proc)
    return _popen()


def discard_ahead() -> None:
    """Ends a process started ahead and not used (the command served no embedded model): it
    holds nothing yet, so it is killed and reaped rather than left to finish its imports."""
    global _ahead
    proc, _ahead = _ahead, None
    if proc is not None:
        with contextlib.suppress(OSError):
            proc.kill()
        close_pipes(proc)
        proc.wait()


def close_pipes(proc: subprocess.Popen) -> None:
    """Its stdin and stdout closed: a model process ends when its stdin does."""
    for pipe in (proc.stdin, proc.stdout):
        with contextlib.suppress(OSError):
            pipe.close()

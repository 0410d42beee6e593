"""The last word on any failure: one line on stderr, never a traceback on the screen.

A known kind of bad input or broken file exits 2 with its reason; anything else is an internal
fault: exit 1, and the traceback goes to a log file under the data dir, named in the line.
"""

from __future__ import annotations

import sys
import tempfile
import time
import traceback
from collections.abc import Callable
from pathlib import Path

from astiop.bounded import one_line

# failures whose message already says what was wrong with the input or the file
KNOWN = (
    "ConfigError",
    "StoreError",
    "LocationError",
    "SpecError",
    "BenchError",
    "SuiteError",
    "EmbeddedModelError",
    "CommandSyntaxError",
    "InterfaceError",
    "LLMError",
    "BackendError",
    "RecordingError",
)


def log_path() -> Path:
    from astiop.config import default_db_path

    folder = default_db_path().parent / "logs"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / "errors.log"
        with probe.open("a"):
            pass
        return probe
    except OSError:
        return Path(tempfile.gettempdir()) / "astiop-errors.log"


def report(exc: BaseException) -> int:
    """Print the one line for `exc` and return the exit code."""
    names = {cls.__name__ for cls in type(exc).__mro__}
    if names & set(KNOWN):
        print(f"astiop: {one_line(exc)}", file=sys.stderr)
        return 2
    if isinstance(exc, RecursionError):
        print("astiop: the input is nested too deeply to read", file=sys.stderr)
        return 2
    path = log_path()
    try:
        with path.open("a", encoding="utf-8") as fh:
            fh.write(f"--- {time.strftime('%Y-%m-%d %H:%M:%S')} argv={sys.argv!r}\n")
            fh.write("".join(traceback.format_exception(exc)))
    except OSError:
        path = Path("(the log could not be written)")
    print(
        f"astiop: internal error: {type(exc).__name__}: {one_line(exc)} (traceback in {path})",
        file=sys.stderr,
    )
    return 1


def usage(exc) -> int:
    """A usage error (unknown option, bad value) in one line, with where to look."""
    where = f" (see: {exc.ctx.command_path} --help)" if getattr(exc, "ctx", None) else ""
    print(f"astiop: {one_line(exc.format_message())}{where}", file=sys.stderr)
    return 2


def guarded(main: Callable[[], object]) -> None:
    try:
        main()
    except KeyboardInterrupt:
        print("astiop: interrupted", file=sys.stderr)
        sys.exit(130)
    except Exception as exc:  # the one place every failure ends
        sys.exit(report(exc))

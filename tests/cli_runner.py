"""The `astiop` command run in this process: the same entry point as the executable (one-line
errors and exit codes included), without paying a Python start-up per call."""

from __future__ import annotations

import contextlib
import io
from types import SimpleNamespace

from astiop.cli import run


def run_cli(*args: str) -> SimpleNamespace:
    out, err = io.StringIO(), io.StringIO()
    code = 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            run(list(args))
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    return SimpleNamespace(returncode=code, stdout=out.getvalue(), stderr=err.getvalue())

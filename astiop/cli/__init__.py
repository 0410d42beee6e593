"""The `astiop` executable: `run()`, light to import (the typer app is in `commands`)."""

from __future__ import annotations

import os
import sys

_VALUED = ("--db", "--model", "--robot", "--ros2-transport")  # global options with a value


def _command(args: list[str]) -> str | None:
    """The subcommand named, read before any option is parsed."""
    after_option = False
    for token in args:
        if after_option:
            after_option = False
        elif token in _VALUED:
            after_option = True
        elif not token.startswith("-"):
            return token
    return None


def run(argv: list[str] | None = None) -> None:
    """The `astiop` executable (argv None: this process is it), or a command run in a process
    that goes on (tests): the app, with one line (never a traceback) for any failure."""
    args = list(sys.argv[1:] if argv is None else argv)
    from astiop.agent import model_spawn

    if _command(args) == "chat":  # the embedded model's process starts before our imports
        model_spawn.start_ahead()
    from astiop.cli.commands import app
    from astiop.cli.common import Ending
    from astiop.cli.errors import guarded, usage

    Ending.at_once = False
    for i, token in enumerate(args):  # `--record` with no FILE: the default file
        if token == "--record" and (i + 1 == len(args) or args[i + 1].startswith("-")):
            args[i] = "--record="

    def main() -> None:
        try:
            code = app(args=args, prog_name="astiop", standalone_mode=False)
        except Exception as exc:  # typer vendors click: its errors are known by class name
            kinds = {cls.__name__ for cls in type(exc).__mro__}
            if "UsageError" in kinds:  # typer would draw a box: one line instead
                sys.exit(usage(exc))
            if "Abort" in kinds:
                print("astiop: aborted", file=sys.stderr)
                sys.exit(1)
            raise
        code = code if isinstance(code, int) else 0
        if argv is None and Ending.at_once:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
        sys.exit(code)

    try:
        guarded(main)
    finally:
        model_spawn.discard_ahead()

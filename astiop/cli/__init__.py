"""The `astiop` executable: `run()`, light to import (the typer app is in `commands`)."""

from __future__ import annotations

import os
import sys

# the app's global options that take a value (a bare `--record` is made `--record=` first)
_VALUED = (
    "--db", "--model", "--robot", "--ros2-transport", "--namespace", "--profile", "--record",
    "--robot-name", "--fleet",
)  # fmt: skip
SERVED_ELSEWHERE = ("rules", "ollama:", "openai:", "dmr:")  # specs with no model process here
ARGS: list[str] = []  # this run's command line (a process it starts may need its options)


def global_args() -> list[str]:
    """This run's options before its command (`--db X --robot ros2` of `astiop --db X ...`)."""
    command, _ = _command_and_model(ARGS)
    return ARGS[: ARGS.index(command)] if command in ARGS else list(ARGS)


def _with_record_file(args: list[str]) -> list[str]:
    """`--record` with no FILE after it: `--record=`, the default file."""
    return [
        "--record=" if t == "--record" and (i + 1 == len(args) or args[i + 1].startswith("-"))
        else t
        for i, t in enumerate(args)
    ]  # fmt: skip


def _command_and_model(args: list[str]) -> tuple[str | None, str | None]:
    """The subcommand and the last --model/-m value, read before typer parses the options."""
    args = _with_record_file(args)
    command = model = None
    i = 0
    while i < len(args):
        token = args[i]
        name, eq, value = token.partition("=")
        following = args[i + 1] if i + 1 < len(args) else None
        takes = not eq and (name in _VALUED or name == "-m")
        if name in ("--model", "-m"):
            model = value if eq else following
        elif command is None and not token.startswith("-"):
            command = token
        i += 2 if takes else 1
    return command, model


def _serves_a_local_model(args: list[str]) -> bool:
    """`astiop chat`, and no flag names a model served elsewhere (the settings may still: then
    the process started ahead ends unused)."""
    command, model = _command_and_model(args)
    return command == "chat" and not (model or "").strip().startswith(SERVED_ELSEWHERE)


def _stops_the_robot(args: list[str]) -> bool:
    """`astiop estop` of every robot on the database: not its --release nor its help, nor the
    stop of one robot of a fleet (its own latch, written once its namespace is known)."""
    command, _ = _command_and_model(args)
    asks = {"--release", "--hold", "--help", "-h", "--robot-name", "--namespace"}
    return command == "estop" and not asks & {a.split("=", 1)[0] for a in args}


def run(argv: list[str] | None = None) -> None:
    """The `astiop` executable (argv None: this process is it), or a command run in a process
    that goes on (tests): the app, with one line (never a traceback) for any failure."""
    args = _with_record_file(list(sys.argv[1:] if argv is None else argv))
    ARGS[:] = args
    if _stops_the_robot(args):  # every other astiop process stops as soon as this is written
        from astiop import estop_sql

        estop_sql.latch_early(args)
    from astiop.agent.models import model_spawn

    if _serves_a_local_model(args):  # the model's process starts before our imports
        model_spawn.start_ahead()
    from astiop.cli.commands import app
    from astiop.cli.common import Ending
    from astiop.cli.errors import guarded, usage

    Ending.at_once = False

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

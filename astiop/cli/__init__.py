"""The `astiop` executable: `run()`, light to import (the typer app is in `commands`)."""

from __future__ import annotations

import ast
import os
import sys
from pathlib import Path


def _valued_options() -> frozenset[str]:
    """The app's global options that take a value, read from the typer.Option declarations of
    `commands.main` without importing typer: this runs before the imports it starts things
    ahead of (a bare `--record` is made `--record=` first)."""
    source = (Path(__file__).parent / "commands.py").read_text(encoding="utf-8")
    main = next(
        node
        for node in ast.parse(source).body
        if isinstance(node, ast.FunctionDef) and node.name == "main"
    )
    args = main.args.args[len(main.args.args) - len(main.args.defaults) :]
    names: set[str] = set()
    for arg, default in zip(args, main.args.defaults, strict=True):
        flag = isinstance(arg.annotation, ast.Name) and arg.annotation.id == "bool"
        if flag or not isinstance(default, ast.Call):
            continue
        names |= {
            c.value
            for c in default.args
            if isinstance(c, ast.Constant) and isinstance(c.value, str) and c.value[:1] == "-"
        }
    return frozenset(names)


_VALUED = _valued_options()
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

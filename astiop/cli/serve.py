"""`astiop serve`: the console in a browser tab, each tab a console process of its own."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

import typer

from astiop.cli.common import CliState, fail, state
from astiop.cli.mcp import loopback


def _global_args(st: CliState) -> list[str]:
    """The options every tab's console and the E-STOP button run with: this command's own, and
    the database resolved now (so a tab never opens another one)."""
    args = ["--db", str(Path(st.db_path).expanduser().resolve())]
    overrides = st.overrides
    if "model" in overrides.get("llm", {}):
        args += ["--model", overrides["llm"]["model"]]
    robot = overrides.get("robot", {})
    if "backend" in robot:
        args += ["--robot", robot["backend"]]
    if "ros2_transport" in robot:
        args += ["--ros2-transport", robot["ros2_transport"]]
    return args


def _robot_said(st: CliState) -> str:
    robot = st.settings.robot
    if robot.backend == "sim":
        return "simulator (one per tab)"
    return f"ros2 ({robot.ros2_transport} transport)"


def serve(
    ctx: typer.Context,
    host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on."),
    port: int = typer.Option(8765, "--port", min=1, max=65535, help="Port to listen on."),
    token_file: Path | None = typer.Option(
        None,
        "--token-file",
        metavar="F",
        help="Ask for the token in F's one line (mode 600) before any console starts; or set "
        "ASTIOP_SERVE_TOKEN. Needed off the loopback.",
    ),
    token_given: str | None = typer.Option(None, "--token", hidden=True),
    max_consoles: int = typer.Option(
        8, "--max-consoles", min=1, max=64, help="Tabs open at once (each is a console process)."
    ),
) -> None:
    """Serve the console to a web browser: every screen, key and dialog, one console process per
    tab on these settings, database and robot, with an E-STOP button on every page."""
    from astiop.bearer_token import SERVE_TOKEN, TokenError, token_from, where

    if token_given is not None:
        fail(f"--token would show the token to every user in `ps`: give it as {where(SERVE_TOKEN)}")
    try:
        token = token_from(token_file, os.environ, SERVE_TOKEN)
    except TokenError as exc:
        fail(str(exc))
    os.environ.pop(SERVE_TOKEN, None)  # never handed down to a console or the robot's processes
    if not loopback(host) and not token:
        fail(f"--host {host} (not the loopback) needs a token ({where(SERVE_TOKEN)}): anyone who "
             "reaches it would get a console that drives the robot")  # fmt: skip
    st = state(ctx)
    st.settings  # a bad settings file fails here, not in every tab  # noqa: B018
    st.store  # the database opens (and is made) once, before any tab  # noqa: B018

    from astiop.web.server import ServeConfig, serve_until_stopped

    base = [sys.executable, "-m", "astiop", *_global_args(st)]
    config = ServeConfig(
        host=host,
        port=port,
        token=token,
        console_argv=base,
        estop_argv=[*base, "estop"],
        db=Path(st.db_path),
        robot=_robot_said(st),
        max_consoles=max_consoles,
    )
    logging.basicConfig(level=logging.INFO, format="astiop serve: %(message)s", stream=sys.stderr)
    access = "the token is asked first" if token else "no token: this machine only"

    def ready(url: str) -> None:
        typer.echo(f"astiop serve: {url} ({access}; robot: {config.robot}); Ctrl-C stops", err=True)

    import asyncio

    try:
        asyncio.run(serve_until_stopped(config, ready))
    except OSError as exc:
        fail(f"cannot listen on {host}:{port}: {exc.strerror or exc}")

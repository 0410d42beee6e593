"""The `astiop` command's typer app: the console by default, and headless subcommands."""

from __future__ import annotations

from pathlib import Path

import typer

from astiop import __version__
from astiop.cli import (
    bench,
    chat,
    config_cmd,
    doctor,
    emulate,
    estop,
    exec_command,
    export,
    fleet,
    locations,
    mcp,
    mission,
    models,
    record,
    replay,
    robot,
    ros2,
    serve,
    sim,
    watch,
    zones,
)
from astiop.cli.common import CliState

app = typer.Typer(
    help="Operator console for the LLM-controlled ASTIbot. With no command, opens the console.",
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)
app.add_typer(config_cmd.app, name="config")
app.add_typer(locations.app, name="locations")
app.add_typer(zones.app, name="zones")
app.add_typer(sim.app, name="sim")
app.add_typer(bench.app, name="bench")
app.add_typer(export.app, name="export")
app.add_typer(ros2.app, name="ros2")
app.add_typer(mission.app, name="mission")
app.add_typer(robot.app, name="robot")
app.add_typer(fleet.app, name="fleet")
app.add_typer(watch.app, name="watch")
app.command("exec")(exec_command.exec_command)
app.command("estop")(estop.estop)
app.command("chat")(chat.chat)
app.command("models")(models.models)
app.command("emulate-ros2")(emulate.emulate_ros2)
app.command("doctor")(doctor.doctor)
app.command("record")(record.record)
app.command("replay")(replay.replay)
app.command("mcp")(mcp.mcp)
app.command("serve")(serve.serve)
app.command("alerts")(watch.alerts)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"astiop {__version__}")
        raise typer.Exit()


@app.callback(invoke_without_command=True)
def main(
    ctx: typer.Context,
    db: Path | None = typer.Option(
        None, "--db", help="SQLite database (default: XDG data dir; env ASTIOP_DB)."
    ),
    model: str | None = typer.Option(
        None,
        "--model",
        help="LLM spec: embedded, rules, ollama:NAME, openai:NAME@URL, dmr:NAME, gguf:PATH.",
    ),
    vision: bool = typer.Option(
        False,
        "--vision",
        help="The --model takes images: a question about the robot's view is sent the camera's "
        "frame (llm.vision).",
    ),
    robot: str | None = typer.Option(None, "--robot", help="Robot backend: sim (default) or ros2."),
    ros2_transport: str | None = typer.Option(
        None,
        "--ros2-transport",
        help="How --robot ros2 talks: rclpy (in process), cli (the ros2 executable) or auto "
        "(rclpy where it and the robot's message packages import).",
    ),
    namespace: str | None = typer.Option(
        None, "--namespace", help="The robot's ROS 2 namespace, e.g. /tb3_1 (robot.namespace)."
    ),
    profile: str | None = typer.Option(
        None,
        "--profile",
        help="Which names play which role: auto (from the robot's graph), a shipped profile "
        "(astibot, turtlebot3_burger, turtlebot3_waffle) or a profile file (robot.profile).",
    ),
    robot_name: str | None = typer.Option(
        None,
        "--robot-name",
        help="One robot of the fleet, by name ([[fleet.robots]], or its namespace with --fleet "
        "auto): every command acts on it.",
    ),
    fleet: str | None = typer.Option(
        None,
        "--fleet",
        help="auto: the fleet is every robot namespace on the ROS 2 domain; list: the "
        "settings' [[fleet.robots]] (fleet.discover).",
    ),
    take: bool = typer.Option(
        False,
        "--take",
        help="Take control of a shared robot from whoever holds it (its lease); without it a "
        "robot another console controls is only watched.",
    ),
    record: str | None = typer.Option(
        None,
        "--record",
        metavar="[FILE]",
        help="Console: record the session as MCAP, to FILE or <data dir>/sessions/<time>.mcap.",
    ),
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    overrides: dict = {}
    if db is not None:
        overrides["db"] = str(db)
    if model is not None:
        overrides.setdefault("llm", {})["model"] = model
    if vision:
        overrides.setdefault("llm", {})["vision"] = True
    if robot is not None:
        overrides.setdefault("robot", {})["backend"] = robot
    if ros2_transport is not None:
        overrides.setdefault("robot", {})["ros2_transport"] = ros2_transport
    if namespace is not None:
        overrides.setdefault("robot", {})["namespace"] = namespace
    if profile is not None:
        overrides.setdefault("robot", {})["profile"] = profile
    if fleet is not None:
        overrides.setdefault("fleet", {})["discover"] = fleet
    ctx.obj = CliState(overrides=overrides, robot_name=robot_name, take=take)
    if ctx.invoked_subcommand is None:
        from astiop.cli.console import run_console

        run_console(ctx.obj, record)

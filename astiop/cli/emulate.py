"""`astiop emulate-ros2`: the simulator as a robot in its own process, with a `ros2` to drive it."""

from __future__ import annotations

import contextlib
import os
import signal
from pathlib import Path

import typer

from astiop.cli.common import fail


def emulate_ros2(
    folder: Path = typer.Option(..., "--dir", help="Where to write the `ros2` executable."),
    distro: str = typer.Option("jazzy", "--distro", help="humble or jazzy: the CLI to emulate."),
    seed: int = typer.Option(0, "--seed", min=0, max=2**32 - 1, help="Seed of the simulator."),
    latency_ms: int = typer.Option(
        300, "--latency-ms", min=0, max=60_000, help="Start-up delay of each ros2 call."
    ),
    missing: list[str] = typer.Option(
        [], "--missing", help="A topic, service or action the robot lacks (repeatable)."
    ),
    speed: float = typer.Option(
        1.0, "--speed", min=0.1, max=20.0, help="Real-time factor of the robot (tests: > 1)."
    ),
    daemon_stopped: bool = typer.Option(
        False, "--daemon-stopped", help="Start with the ros2 daemon down, as on a fresh boot."
    ),
    dds: bool = typer.Option(
        False,
        "--dds",
        help="No simulator: run each verb over real DDS (rclpy) against the robot on the domain.",
    ),
) -> None:
    """Run an emulated robot until Ctrl-C (or SIGTERM); put DIR on PATH and use `astiop --robot ros2`."""
    from astiop.robot_programs.emulated_cli.robot import EmulatedRobot, write_client
    from astiop.ros2.cli_args import DISTROS

    if distro not in DISTROS:
        fail(f"--distro must be one of {', '.join(DISTROS)}, not '{distro}'")
    if dds and missing:
        fail("--missing is the emulated robot's; with --dds the robot on the domain is used")
    folder = folder.expanduser().resolve()
    if len(str(folder / "robot.sock")) > 100:
        fail(f"--dir {folder} is too long for a Unix socket path; use a shorter one")
    try:
        exe = write_client(folder, distro=distro, latency_ms=latency_ms, missing=tuple(missing))
        os.environ["ROS_DISTRO"] = distro  # as a sourced ROS 2 sets it, for the robot's types
        robot = (
            _dds_server(distro, daemon_stopped)
            if dds
            else EmulatedRobot(
                folder,
                seed=seed,
                distro=distro,
                missing=tuple(missing),
                speed=speed,
                daemon_running=not daemon_stopped,
            )
        )
    except OSError as exc:
        fail(f"cannot set up {folder}: {exc.strerror or exc}")
    what = f"ROS 2 {distro} CLI over DDS (domain {os.environ.get('ROS_DOMAIN_ID', '0')})"
    typer.echo(
        f"emulated {what if dds else f'ROS 2 {distro} robot'} ready: {exe}\n"
        f'  export PATH="{folder}:$PATH" ROS_DISTRO={distro}; astiop --robot ros2\n'
        "  every call is logged to " + str(folder / "ros2.log") + "; Ctrl-C stops the robot",
        err=True,
    )
    # Stop on Ctrl-C or SIGTERM even when started with SIGINT ignored (a script's `&` job).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    with contextlib.suppress(KeyboardInterrupt):
        robot.serve(str(folder / "robot.sock"))


def _dds_server(distro: str, daemon_stopped: bool):
    try:
        from astiop.robot_programs.emulated_cli.dds import DdsRos2
    except ImportError as exc:
        fail(f"--dds needs rclpy: {exc}")
    server = DdsRos2(distro)
    server.daemon_running = not daemon_stopped
    return server

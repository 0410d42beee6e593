"""`astiop ros2`: the robot's interface packages, built here or exported for a robot."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from astiop.cli.common import fail

app = typer.Typer(
    help="The robot's ROS 2 interface packages (astiop_msgs, and nav2_msgs/tf2_msgs subsets).",
    no_args_is_help=True,
)


@app.command("build-interfaces")
def build_interfaces(
    prefix: Path | None = typer.Option(
        None,
        "--prefix",
        help="The ROS 2 prefix to install into (default: this Python's environment, where the "
        "astiop[ros] wheels are).",
    ),
) -> None:
    """Build astiop_msgs (and nav2_msgs/tf2_msgs subsets where they are not installed) with
    cmake; a second run with nothing changed does nothing."""
    from astiop.ros2.interface_build import BuildError, build

    target = (prefix or Path(sys.prefix)).expanduser().resolve()
    if not target.is_dir():
        fail(f"--prefix {target} is not a folder")
    try:
        report = build(target, say=lambda line: typer.echo(line, err=True))
    except BuildError as exc:
        fail(str(exc))
    except OSError as exc:
        fail(f"cannot build into {target}: {exc.strerror or exc}")
    for package, why in report.skipped.items():
        typer.echo(f"{package}: not built, {why}", err=True)
    if report.built:
        typer.echo(f"built {', '.join(report.built)} in {report.seconds:.1f} s into {target}")
    if report.up_to_date:
        typer.echo(f"up to date: {', '.join(report.up_to_date)}")


@app.command("export-interfaces")
def export_interfaces(
    folder: Path = typer.Argument(..., help="Where to write the packages (a colcon src/ folder)."),
    distro: str = typer.Option(
        "jazzy", "--distro", help="humble, jazzy or kilted: the robot's ROS 2 distribution."
    ),
) -> None:
    """Write the interface packages' sources for `colcon build` on a robot."""
    from astiop.ros2.interface_build import export_packages

    if distro not in ("humble", "jazzy", "kilted"):
        fail(f"--distro must be humble, jazzy or kilted, not '{distro}'")
    try:
        written = export_packages(folder.expanduser(), distro)
    except OSError as exc:
        fail(f"cannot write {folder}: {exc.strerror or exc}")
    for root in written:
        typer.echo(str(root))
    typer.echo(
        "on the robot: colcon build --packages-select astiop_msgs (and nav2_msgs/tf2_msgs only "
        "where they are not installed), then source install/setup.bash",
        err=True,
    )

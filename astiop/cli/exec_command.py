"""`astiop exec`: one ros2 command through validation and safety, on the sim or the robot."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

import typer

from astiop.cli.common import fail, interactive, print_json, state, take_control

if TYPE_CHECKING:
    from astiop.ros2.validation import Checked


def _to_the_robot_named(st, command: str) -> None:
    """A fleet and no --robot-name: a command whose names are under one robot's namespace
    (`/astibot_2/cmd_vel`) goes to that robot, as if named (its profile, its lease, its
    E-STOP); one naming none goes to the whole domain."""
    from astiop.cli.fleet import members
    from astiop.robot.fleet import is_fleet

    if st.robot_name is not None or not is_fleet(st.fleet_settings):
        return
    under = set(re.findall(r"""(?:^|[\s'"])/([A-Za-z][A-Za-z0-9_]*)/""", command))
    if not under:
        return
    robots = {r.namespace.strip("/"): r.name for r in members(st)}
    named = sorted(robots[ns] for ns in under if ns in robots)
    if len(named) > 1:
        fail(f"one robot per command: this one names {' and '.join(named)}")
    if named:
        st.address(named[0])
        typer.echo(f"to {named[0]} (its names)", err=True)


def exec_command(
    ctx: typer.Context,
    command: str = typer.Argument(..., help='One ros2 command, quoted: "ros2 topic echo /odom"'),
    dry_run: bool = typer.Option(False, "--dry-run", help="Validate only; run nothing."),
    yes: bool = typer.Option(False, "--yes", "-y", help="Do not ask before moving the robot."),
    as_json: bool = typer.Option(False, "--json"),
    settle: bool = typer.Option(
        True, help="Let a started goal finish before exiting (on the sim: as fast as it can)."
    ),
) -> None:
    """Validate and run one `ros2` command (the subset the agent uses) on the robot."""
    from astiop.robot.factory import make_robot_gateway
    from astiop.transports.base import BackendError  # numpy: for the commands that use it

    st = state(ctx)
    _to_the_robot_named(st, command)
    try:
        gateway = make_robot_gateway(st.settings, st.store)
    except BackendError as exc:
        fail(str(exc))
    review = gateway.review(command)
    if not dry_run and (st.take or review.checked.kind == "actuate"):
        take_control(gateway, st)  # --take: even where a half-read graph left the command unknown
    if dry_run:
        c = review.checked
        data = {
            "command": command,
            "valid": c.valid and review.allowed,
            "reason": review.reason or c.reason,
            "kind": c.kind,
            "executed": False,
            "output": "",
            "values": c.message,
        }
        if as_json:
            print_json(data)
        else:
            typer.echo(
                f"{'valid' if data['valid'] else 'rejected'} ({c.kind})"
                + (f": {data['reason']}" if data["reason"] else "")
            )
        raise typer.Exit(0 if data["valid"] else 2)

    def ask(checked: Checked) -> bool:
        return typer.confirm(f"run '{checked.command.display()}' (it moves the robot)?")

    # no terminal to ask on and no --yes: the graph refuses actuating commands
    confirm = (lambda _c: True) if yes else (ask if interactive() else None)
    result = gateway.run(command, confirm=confirm, source="exec")
    if result.executed and settle and result.kind == "actuate":
        gateway.wait_until_idle(900.0)
    gateway.close()
    if as_json:
        print_json(result.as_json())
    else:
        if result.output:
            typer.echo(result.output, nl=False)
        for note in result.notes:
            typer.echo(f"note: {note}", err=True)
    if not result.executed:
        reason = result.reason
        if reason.startswith("this command moves") and not yes:
            reason += " (pass --yes)"
        if not as_json:
            fail(reason)
        raise typer.Exit(2)
    if result.error:
        if not as_json:
            typer.echo(f"astiop: {result.error}", err=True)
        raise typer.Exit(1)

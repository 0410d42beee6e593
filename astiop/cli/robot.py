"""`astiop robot profile`: which of the robot's names play which role, why, and what is missing;
`--write FILE` starts a profile file from what was matched."""

from __future__ import annotations

from pathlib import Path

import typer

from astiop.cli.common import fail, print_json, state

app = typer.Typer(help="The robot as astiop reads it.", no_args_is_help=True)


@app.command("profile")
def profile(
    ctx: typer.Context,
    as_json: bool = typer.Option(False, "--json"),
    write: Path | None = typer.Option(
        None, "--write", metavar="FILE", help="Write a profile file from what was matched."
    ),
    force: bool = typer.Option(False, "--force", help="With --write: replace an existing file."),
) -> None:
    """Each role (pose, battery, scan, map, velocity command, navigation, stop, dock, ...), the
    name on the robot that plays it and why, and the roles the robot lacks."""
    from astiop.robot.factory import make_robot_gateway
    from astiop.ros2.profile_file import write_profile
    from astiop.transports.base import BackendError

    st = state(ctx)
    if write is not None and write.exists() and not force:
        fail(f"{write} exists (--force replaces it)")
    try:
        gateway = make_robot_gateway(st.settings, st.store)
    except BackendError as exc:
        fail(str(exc))
    try:
        found = gateway.settled_profile(st.settings.robot.ros2_timeout_s)
    finally:
        gateway.close()
    if write is not None:
        try:
            write.write_text(write_profile(found), encoding="utf-8")
        except OSError as exc:
            fail(f"cannot write {write}: {exc.strerror}")
    if as_json:
        print_json(found.as_dict())
        return
    typer.echo(f"robot: {found.make}" + (f" under {found.namespace}" if found.namespace else ""))
    typer.echo(f"profile: {found.source}")
    width = max(len(r) for r in found.matches)
    for role, m in found.matches.items():
        if m.name:
            typer.echo(f"  {role:<{width}}  {m.name}  {m.type} ({m.why})")
        else:
            typer.echo(f"  {role:<{width}}  -  ({m.why})")
    units = found.units.battery_percentage or "fraction (a reading over 1 as percent)"
    typer.echo(f"battery percentage: {units}")
    limits = found.as_dict()["limits"]
    if limits:
        typer.echo("limits: " + ", ".join(f"{k} {v:g}" for k, v in limits.items()))
    fence = found.map.geofence
    where = "geofence " + ", ".join(f"{v:g}" for v in fence) if fence else "geofence: its /map"
    typer.echo(f"map: {found.map_name} (its named places belong to it; {where})")
    missing = found.missing()
    typer.echo("missing: " + (", ".join(missing) if missing else "nothing"))
    if write is not None:
        typer.echo(f"wrote {write}: read it with --profile {write}")

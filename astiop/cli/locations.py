"""`astiop locations`: the named locations the agent and the operator send the robot to."""

from __future__ import annotations

import math

import typer

from astiop.bounded import escape_controls
from astiop.cli.common import fail, print_json, state

app = typer.Typer(help="List, show, add, rename and remove named locations.", no_args_is_help=True)


@app.command("list")
def list_locations(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """List every named location."""
    locations = state(ctx).store.list_locations()
    if as_json:
        print_json([loc.as_json() for loc in locations])
        return
    if not locations:
        typer.echo("no named locations")
        return
    width = max(len(loc.name) for loc in locations)
    typer.echo(f"{'name':<{width}}  {'x':>7}  {'y':>7}  {'theta':>7}  description")
    for loc in locations:
        typer.echo(
            f"{loc.name:<{width}}  {loc.x:7.2f}  {loc.y:7.2f}  "
            f"{math.degrees(loc.theta):6.1f}°  {escape_controls(loc.description)}"
        )


@app.command("show")
def show(ctx: typer.Context, name: str, as_json: bool = typer.Option(False, "--json")) -> None:
    """Show one location."""
    from astiop.store import LocationError  # sqlite-utils: imported by the command that needs it

    try:
        loc = state(ctx).store.require_location(name)
    except LocationError as exc:
        fail(str(exc))
    if as_json:
        print_json([loc.as_json()])
    else:
        typer.echo(
            f"{loc.name}: x={loc.x:.3f} m  y={loc.y:.3f} m  theta={math.degrees(loc.theta):.1f}°"
            + (f"  ({escape_controls(loc.description)})" if loc.description else "")
        )


@app.command("add")
def add(
    ctx: typer.Context,
    name: str,
    x: float = typer.Argument(..., help="metres, map frame"),
    y: float = typer.Argument(..., help="metres, map frame"),
    theta_deg: float = typer.Argument(0.0, help="heading in degrees, counter-clockwise from +x"),
    description: str = typer.Option("", "--description", "-d"),
) -> None:
    """Add a named location at X Y (metres) facing THETA_DEG."""
    from astiop.store import LocationError  # sqlite-utils: imported by the command that needs it

    try:
        loc = state(ctx).store.add_location(name, x, y, math.radians(theta_deg), description)
    except LocationError as exc:
        fail(str(exc))
    typer.echo(f"added {loc.name} at ({loc.x:.2f}, {loc.y:.2f}, {math.degrees(loc.theta):.1f}°)")


@app.command("rename")
def rename(ctx: typer.Context, old: str, new: str) -> None:
    """Rename a location."""
    from astiop.store import LocationError  # sqlite-utils: imported by the command that needs it

    try:
        loc = state(ctx).store.rename_location(old, new)
    except LocationError as exc:
        fail(str(exc))
    typer.echo(f"renamed {old} to {loc.name}")


@app.command("remove")
def remove(ctx: typer.Context, name: str) -> None:
    """Remove a location."""
    from astiop.store import LocationError  # sqlite-utils: imported by the command that needs it

    try:
        loc = state(ctx).store.remove_location(name)
    except LocationError as exc:
        fail(str(exc))
    typer.echo(f"removed {loc.name}")

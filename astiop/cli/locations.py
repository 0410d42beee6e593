"""`astiop locations`: the named locations the agent and the operator send the robot to."""

from __future__ import annotations

import math

import typer

from astiop.bounded import escape_controls
from astiop.cli.common import fail, print_json, state

app = typer.Typer(
    help="List, show, add, rename and remove named locations (each belongs to a robot's map).",
    no_args_is_help=True,
)


def robots_map(settings) -> tuple[str, tuple[float, float, float, float] | None]:
    """The map the settings' robot is on: the simulator's warehouse, else what its profile
    (file or shipped) says, else its profile as read on its graph (the robot reached)."""
    from astiop.robot.factory import make_robot_gateway, profile_spec
    from astiop.ros2.profile_file import shipped
    from astiop.warehouse import default_map

    if settings.robot.backend != "ros2":
        return "warehouse", default_map().bounds
    spec = profile_spec(settings)
    base = shipped(spec.make)
    where = spec.map.over(base.map) if base is not None else spec.map
    if where.name or spec.make:
        name = where.name or spec.make
        fence = where.geofence or (default_map().bounds if name == "warehouse" else None)
        return name, fence
    gateway = make_robot_gateway(settings, None, who="locations")  # its make, from its graph
    try:
        profile = gateway.settled_profile(settings.robot.ros2_timeout_s)
        gateway.use_map()
        return profile.map_name, gateway.safety.geofence
    finally:
        gateway.close()


@app.callback()
def on_map(
    ctx: typer.Context,
    map_name: str = typer.Option(
        "",
        "--map",
        help="The map whose places these are (default: the robot's, by its profile; the "
        "simulator's is warehouse).",
    ),
) -> None:
    from astiop.transports.base import BackendError

    st = state(ctx)
    if map_name:  # said: no robot need be reached
        st.store.use_map(map_name, None)
        return
    try:
        name, fence = robots_map(st.settings)
    except BackendError as exc:
        fail(f"the robot's map is not known ({exc}): name it with --map NAME")
    st.store.use_map(name, fence)


@app.command("list")
def list_locations(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """List the named locations of the robot's map."""
    store = state(ctx).store
    locations = store.list_locations()
    if as_json:
        print_json([loc.as_json() for loc in locations])
        return
    if not locations:
        others = ", ".join(f"{m} ({n})" for m, n in sorted(store.other_maps().items()))
        typer.echo(
            f"no named locations on the map {store.map_name}"
            + (f" (other maps: {others}; --map NAME lists one)" if others else "")
        )
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


@app.command("move")
def move(
    ctx: typer.Context,
    name: str,
    to_map: str = typer.Option(..., "--to-map", help="The map it belongs to."),
) -> None:
    """Move a location to another map (one saved on the wrong robot's map)."""
    from astiop.store import LocationError  # sqlite-utils: imported by the command that needs it

    store = state(ctx).store
    here = store.map_name
    try:
        loc = store.move_location(name, to_map)
    except LocationError as exc:
        fail(str(exc))
    typer.echo(f"moved {loc.name} from the map {here} to {to_map}")


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

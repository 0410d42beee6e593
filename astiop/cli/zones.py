"""`astiop zones`: keepout and speed zones of a robot's map, and their Nav2 filter masks."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from astiop.cli.common import fail, print_json, state
from astiop.zones import MapZone, ZoneError, parse_corner

app = typer.Typer(
    help="List, show, add, rename and remove the zones of a robot's map (keepout: no goal "
    "inside, no plan through; speed: a lower limit inside), and export them for Nav2.",
    no_args_is_help=True,
)


@app.callback()
def on_map(
    ctx: typer.Context,
    map_name: str = typer.Option(
        "",
        "--map",
        help="The map whose zones these are (default: the robot's, by its profile; the "
        "simulator's is warehouse).",
    ),
) -> None:
    from astiop.cli.locations import on_map as places_map

    places_map(ctx, map_name)  # zones belong to the map the places do


def _line(zone: MapZone) -> str:
    corners = " ".join(f"{x:g},{y:g}" for x, y in zone.corners)
    limit = f" {zone.speed:g} m/s" if zone.kind == "speed" else ""
    return f"{zone.kind}{limit}  {corners}"


@app.command("list")
def list_zones(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """List the zones of the robot's map."""
    store = state(ctx).store
    zones = store.list_zones()
    if as_json:
        print_json([z.as_json() for z in zones])
        return
    if not zones:
        typer.echo(f"no zones on the map {store.map_name}")
        return
    width = max(len(z.name) for z in zones)
    for zone in zones:
        typer.echo(f"{zone.name:<{width}}  {_line(zone)}")


@app.command("show")
def show(ctx: typer.Context, name: str, as_json: bool = typer.Option(False, "--json")) -> None:
    """Show one zone."""
    try:
        zone = state(ctx).store.require_zone(name)
    except ZoneError as exc:
        fail(str(exc))
    if as_json:
        print_json([zone.as_json()])
    else:
        typer.echo(f"{zone.name}: {_line(zone)}")


@app.command("add", context_settings={"ignore_unknown_options": True})
def add(
    ctx: typer.Context,
    name: str,
    corners: list[str] = typer.Argument(None, help="x,y corners in metres, in order around it"),
    keepout: bool = typer.Option(False, "--keepout", help="No goal inside, no plan through."),
    speed: str = typer.Option("", "--speed", help="A speed zone: its limit inside, m/s."),
) -> None:
    """Add a zone: `add loading_bay --keepout 1,2 4,2 4,5 1,5`, `add aisle --speed 0.3 ...`."""
    if keepout == bool(speed):
        fail("say --keepout or --speed LIMIT (m/s), one of the two")
    try:
        limit = None
        if speed:
            try:
                limit = float(speed)
            except ValueError:
                raise ZoneError(f"bad speed '{speed[:40]}': a limit in m/s") from None
        points = [parse_corner(c) for c in corners or []]
        kind = "keepout" if keepout else "speed"
        zone = state(ctx).store.add_zone(name, kind, points, limit)
    except ZoneError as exc:
        fail(str(exc))
    typer.echo(f"added {zone.words} on the map {state(ctx).store.map_name}")


@app.command("rename")
def rename(ctx: typer.Context, old: str, new: str) -> None:
    """Rename a zone."""
    try:
        zone = state(ctx).store.rename_zone(old, new)
    except ZoneError as exc:
        fail(str(exc))
    typer.echo(f"renamed {old} to {zone.name}")


@app.command("remove")
def remove(ctx: typer.Context, name: str) -> None:
    """Remove a zone."""
    try:
        zone = state(ctx).store.remove_zone(name)
    except ZoneError as exc:
        fail(str(exc))
    typer.echo(f"removed {zone.words}")


@app.command("export")
def export(
    ctx: typer.Context,
    nav2: Path = typer.Option(..., "--nav2", help="The folder to write Nav2's masks into."),
    resolution: float = typer.Option(0.05, "--resolution", help="m per pixel"),
) -> None:
    """Write Nav2's keepout and speed filter masks (PGM + YAML) and the parameters of their
    costmap_filter_info_server and map_server nodes."""
    from astiop import nav2_masks

    store = state(ctx).store
    if not (math.isfinite(resolution) and 0.005 <= resolution <= 1.0):
        fail("--resolution is in m per pixel, 0.005..1")
    zones = store.list_zones()
    bounds = store.bounds
    if bounds is None:
        if not zones:
            fail(f"the map {store.map_name} has no zones and no known extent: nothing to export")
        xs = [x for z in zones for x, _ in z.corners]
        ys = [y for z in zones for _, y in z.corners]
        bounds = (min(xs) - 1, min(ys) - 1, max(xs) + 1, max(ys) + 1)
    if (bounds[2] - bounds[0]) * (bounds[3] - bounds[1]) / resolution**2 > 50e6:
        fail("the masks would exceed 50 million pixels: use a coarser --resolution")
    try:
        files = nav2_masks.export(zones, bounds, nav2, resolution)
    except OSError as exc:
        fail(f"cannot write {nav2}: {exc.strerror or exc}")
    kinds = {k: sum(z.kind == k for z in zones) for k in ("keepout", "speed")}
    typer.echo(
        f"wrote {len(files)} files to {nav2} ({kinds['keepout']} keepout, {kinds['speed']} "
        f"speed zones; {resolution:g} m/pixel); load costmap_filter_info.yaml's nodes"
    )

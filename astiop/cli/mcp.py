"""`astiop mcp`: serve the robot to MCP clients (Claude, Cursor, any agent) through the one door."""

from __future__ import annotations

import ipaddress
import os
import sys
import threading
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from astiop.cli.common import fail, state, take_control

if TYPE_CHECKING:
    from astiop.robot.fleet import FleetFinder


def parse_http(value: str) -> tuple[str, int]:
    """`[HOST:]PORT` -> (host, port); the host is 127.0.0.1 when omitted."""
    host, _, port = value.rpartition(":")
    host = host.strip("[]") or "127.0.0.1"
    if not port.isdigit() or not 0 < int(port) < 65536:
        fail(f"--http wants [HOST:]PORT with a port from 1 to 65535, not {value!r}")
    return host, int(port)


def loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def mcp(
    ctx: typer.Context,
    http: str | None = typer.Option(
        None, "--http", metavar="[HOST:]PORT", help="Serve streamable HTTP (default: stdio)."
    ),
    token_file: Path | None = typer.Option(
        None,
        "--token-file",
        metavar="F",
        help="Require 'Authorization: Bearer TOKEN', TOKEN the one line of F (mode 600); or set "
        "ASTIOP_MCP_TOKEN. Needed off the loopback.",
    ),
    token_given: str | None = typer.Option(None, "--token", hidden=True),
    read_only: bool = typer.Option(
        False, "--read-only", help="Register no tool that acts on the robot."
    ),
    approve_actuation: bool = typer.Option(
        False,
        "--approve-actuation",
        help="Allow actuation without a console's approval (still clamped, geofenced, logged).",
    ),
    approval_timeout: float = typer.Option(
        60.0, "--approval-timeout", min=1.0, max=3600.0, help="Seconds a console has to answer."
    ),
) -> None:
    """Serve the robot to MCP clients: reads freely; each actuation approved in a console."""
    from astiop.bearer_token import MCP_TOKEN, TokenError, token_from, where

    if token_given is not None:
        fail(f"--token would show the token to every user in `ps`: give it as {where(MCP_TOKEN)}")
    host, port = parse_http(http) if http is not None else ("", 0)
    if token_file is not None and http is None:
        fail("--token-file goes with --http (stdio needs none)")
    token = None
    if http is not None:
        try:
            token = token_from(token_file, os.environ, MCP_TOKEN)
        except TokenError as exc:
            fail(str(exc))
    os.environ.pop(MCP_TOKEN, None)  # not handed down to the robot's `ros2` processes
    if http is not None and not loopback(host) and not token:
        fail(f"--http on {host} (not the loopback) needs a token ({where(MCP_TOKEN)}): anyone who "
             "reaches it could ask the robot to move")  # fmt: skip

    from astiop.mcp.approval import Policy
    from astiop.mcp.fleet_tools import FleetTools
    from astiop.mcp.server import AstiopMCP, serve_http, serve_stdio
    from astiop.mcp.tools import RobotTools
    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.fleet import is_fleet
    from astiop.robot.fleet_watch import FIND_S
    from astiop.transports.base import BackendError

    st = state(ctx)
    policy = Policy(approve_actuation=approve_actuation, timeout_s=approval_timeout)
    finder = None  # a fleet found on the graph: looked for again while serving
    robots = None
    if is_fleet(st.fleet_settings) and st.robot_name is None:
        robots, finder = _robots(st)
    try:
        gateways = {name: make_robot_gateway(settings, st.store, realtime=True, who="astiop mcp")
                    for name, settings in (robots or {"": st.settings}).items()}  # fmt: skip
    except BackendError as exc:
        fail(str(exc))
    if robots is None and not read_only:
        take_control(gateways[""], st)  # a fleet's robots: each when first moved, if free
    tools = {name: RobotTools(gw, st.store, policy) for name, gw in gateways.items()}
    fleet = FleetTools(tools) if robots else None
    server = AstiopMCP(fleet or tools[""], read_only=read_only)
    if read_only:
        mode = "read-only"
    elif approve_actuation:
        mode = "actuation allowed by the operator (--approve-actuation)"
    else:
        mode = "actuation needs a console's approval"
    where = f"http://{host}:{port}/mcp" if http else "stdio"
    what = f"{len(robots)} robots ({', '.join(robots)})" if robots else f"robot {gateways[''].kind}"
    print(f"astiop mcp: serving on {where}; {what}; {mode}", file=sys.stderr)
    for gateway in gateways.values():
        gateway.start()
    halt = threading.Event()
    if fleet is not None and finder is not None:
        fleet.keep_adding(
            lambda: [r.name for r in finder.poll()],
            partial(_joined, st, finder, policy, gateways),
            FIND_S,
            halt,
        )
    try:
        if http is not None:
            serve_http(server, host, port, token)
        else:
            serve_stdio(server)
    finally:
        halt.set()
        if finder is not None:
            finder.close()
        for gateway in list(gateways.values()):
            gateway.close()


def _joined(st, finder, policy, gateways: dict, name: str):
    """The tools of a robot found while serving, its gateway started (and kept in `gateways`,
    closed at the end); said on stderr. A robot not reached is said and looked for again."""
    from astiop.mcp.tools import RobotTools
    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.fleet import robot_settings

    robot = finder.found[name]
    try:
        gateway = make_robot_gateway(
            robot_settings(st.fleet_settings, name), st.store, realtime=True, who="astiop mcp"
        )
    except Exception as exc:
        finder.found.pop(name, None)
        print(f"astiop mcp: {name} ({robot.namespace}) found, not reached: {exc}", file=sys.stderr)
        raise
    gateways[name] = gateway
    gateway.start()
    print(f"astiop mcp: {name} ({robot.namespace}) joined: served from now", file=sys.stderr)
    return RobotTools(gateway, st.store, policy)


def _robots(st) -> tuple[dict, FleetFinder | None]:
    """The fleet's robots found, each name with its own settings (said on stderr as found), and
    for a fleet found on the graph its finder, to serve the robots that join later."""
    from astiop.robot.fleet import (
        FOUND_ONCE_S,
        FleetError,
        FleetFinder,
        find_robots,
        robot_settings,
    )

    whole = st.fleet_settings
    print("astiop mcp: finding the fleet's robots…", file=sys.stderr)

    def said(robot) -> None:
        print(f"  {robot.name} ({robot.namespace})", file=sys.stderr)

    finder = None
    try:
        if whole.fleet.discover == "auto":
            finder = FleetFinder(whole)
            found = finder.settle(said, FOUND_ONCE_S)
        else:
            found = find_robots(whole, said)
    except FleetError as exc:
        if finder is not None:
            finder.close()
        fail(str(exc))
    return {r.name: robot_settings(whole, r.name) for r in found}, finder

"""The MCP server on the official SDK: the tools of `astiop.mcp.tools` registered with their
class, every call recorded as an interaction (source mcp, the client's name), every failure one
line to the client, and the two transports (stdio; streamable HTTP behind an optional token)."""

from __future__ import annotations

import hmac
import json
import logging
import threading
import time
from typing import Any

import anyio
from mcp import types
from mcp.server.mcpserver import Context, MCPServer
from mcp.server.mcpserver.exceptions import ToolError
from mcp.server.subscriptions import InMemorySubscriptionBus
from mcp.types import CallToolResult, TextContent, ToolAnnotations
from pydantic import ValidationError

from astiop import __version__
from astiop.bounded import escape_controls, one_line
from astiop.mcp.alerts import ALERTS_URI, AlertFeed
from astiop.mcp.fleet_tools import FleetTools
from astiop.mcp.tools import CALL, TOOL_CLASSES, Call, Refused, RobotTools
from astiop.ros2.interfaces import InterfaceError, interface_show

MAX_CALLS = 16  # calls served at once; more are refused at once (a flood)
INSTRUCTIONS = (
    "astiop drives a warehouse robot. Read tools never move it. Actuating tools need a "
    "person's approval and may be refused with a reason; a goal returns when it is accepted, "
    "and robot_state reports how it ended. stop and estop always work."
)
DESCRIPTIONS = {
    "fleet_status": "Every robot this server reaches: name, state, battery, pose, speed, goal "
    "and who controls it, as each last reported. Every other tool takes robot: one of these "
    "names (left out: the only robot).",
    "robot_state": "The robot's pose, battery, status and faults as it last reported them, "
    "each with age_s (seconds since that report); and the last goal's outcome.",
    "list_locations": "The named locations: name, x and y (m, map frame), theta_deg, description.",
    "read_topic": "One message from a ROS 2 topic (ros2 topic echo TOPIC --once), e.g. "
    "/battery_status.",
    "ros2_query": "Run one read-only ros2 command line (topic list/info/echo/hz, service list, "
    "interface show, param get). Lines that act on the robot are refused.",
    "camera_frame": "The robot's current camera frame as a PNG image, with its topic, size and "
    "age (seconds since the robot published it); one line of text when there is no camera or "
    "no frame yet.",
    "go_to_location": "Send the robot to a named location (see list_locations). Needs the "
    "operator's approval. Returns when the goal is accepted, not when it is reached.",
    "go_to_pose": "Send the robot to x, y (m, map frame) facing theta_deg. Needs approval; "
    "refused outside the geofence. Returns when the goal is accepted.",
    "move": "Drive at vx, vy (m/s, robot frame) and wz (rad/s) for seconds (at most 3), then "
    "stop. Needs approval; speeds are clamped to the robot's limits.",
    "dock": "Drive onto the charging dock. Needs approval.",
    "undock": "Back off the charging dock. Needs approval.",
    "stop": "Stop motion and cancel the goal now. Always allowed; no approval.",
    "estop": "Engage the E-STOP: stop and latch it; nothing moves until the operator releases "
    "it. Always allowed; no approval.",
    "ros2_command": "Run one ros2 command line through astiop's validation and safety. Lines "
    "that move the robot need approval.",
    "start_mission": "Run steps one after the other, each starting when the one before has "
    "ended as the robot reported it: {kind: goto, place | x, y}, {kind: dock|undock|load|unload}, "
    "{kind: wait, seconds}, {kind: read, what: battery|obstacles}; any step may hold "
    "'if': {what: battery|obstacles, op: '<'|'>', value}. One approval shows every step. "
    "A failed step ends the mission. One mission per robot: replace: true replaces the "
    "running one (the approval says so); until_stopped: true repeats the steps until "
    "cancel_mission.",
    "mission_status": "A mission (default: the latest): each step's status, detail and the "
    "robot's pose at its end, as stored.",
    "cancel_mission": "Cancel the running mission (default) and stop the robot; drops an "
    "interrupted one. Always allowed.",
    "list_alerts": "The alerts that watches and the built-in alerts fired (battery low, fault, "
    "contact lost, E-STOP, goal aborted, no progress, mission failed, ...), newest first: "
    "open_only (default) those not yet acknowledged; robot and kind filter them. The resource "
    "astiop://alerts holds the open ones and can be subscribed to.",
    "acknowledge_alert": "Acknowledge an alert by its id (from list_alerts): every station "
    "then shows it as acknowledged by this client. Moves nothing.",
}


def client_name(context: Context | None) -> str:
    try:
        params = context.session.client_params if context is not None else None
        name = params.client_info.name if params is not None else ""
    except Exception:  # noqa: BLE001 - no session outside a request
        name = ""
    return one_line(escape_controls(str(name or "unknown")), 64)


def describe(name: str, arguments: dict[str, Any]) -> str:
    """The call as the record and the approving person see it, bounded."""
    try:
        args = json.dumps(arguments, ensure_ascii=False, default=str)
    except (TypeError, ValueError):
        args = repr(arguments)
    return one_line(escape_controls(f"{name[:64]} {args}"), 600)


def reason_of(name: str, exc: BaseException) -> str:
    """One line for the client, whatever went wrong."""
    cause = exc.__cause__
    while cause is not None and not isinstance(cause, (Refused, ValidationError)):
        cause = cause.__cause__
    if isinstance(cause, Refused):
        return one_line(cause, 500)
    if isinstance(cause, ValidationError):
        parts = [
            f"{'.'.join(str(p) for p in e['loc']) or 'arguments'}: {e['msg']}"
            for e in cause.errors()[:4]
        ]
        return one_line(f"bad arguments for {name[:64]}: " + "; ".join(parts), 500)
    if exc.__cause__ is not None and "Unexpected" in type(exc).__name__:
        inner = exc.__cause__
        return one_line(f"internal error in {name[:64]}: {type(inner).__name__}: {inner}", 500)
    return one_line(escape_controls(str(exc)), 500)


class AstiopMCP(MCPServer):
    def __init__(self, robot: RobotTools | FleetTools, read_only: bool = False):
        if isinstance(robot, RobotTools):  # one robot: a fleet of one, named for its namespace
            robot = FleetTools({robot.gateway.profile.namespace.strip("/") or "robot": robot})
        bus = InMemorySubscriptionBus()  # subscriptions/listen streams, told of alerts too
        self.alerts = AlertFeed(robot.first.store, bus)
        super().__init__(
            "astiop", instructions=INSTRUCTIONS, version=__version__, log_level="WARNING",
            subscriptions=bus, lifespan=self.alerts.watching,
        )  # fmt: skip
        # resources/subscribe of a 2025-era client: MCPServer serves subscriptions/listen only
        lowlevel = self._lowlevel_server
        lowlevel.add_request_handler(
            "resources/subscribe", types.SubscribeRequestParams, self.alerts.subscribe
        )
        lowlevel.add_request_handler(
            "resources/unsubscribe", types.UnsubscribeRequestParams, self.alerts.unsubscribe
        )
        self.fleet = robot
        self.robot = robot.first  # the store's audit trail, and the resources' robot
        self.read_only = read_only
        self._slots = threading.BoundedSemaphore(MAX_CALLS)
        for name, cls in TOOL_CLASSES.items():
            if read_only and cls != "read":
                continue
            self.add_tool(
                self._tool(robot, name),
                name=name,
                description=DESCRIPTIONS[name],
                annotations=ToolAnnotations(
                    read_only_hint=cls == "read",
                    destructive_hint=False
                    if cls == "read"
                    else name not in ("stop", "cancel_mission", "acknowledge_alert"),
                    open_world_hint=True,
                ),
                meta={"astiop/class": cls},
            )
        self._resources()

    def _tool(self, robot: FleetTools, name: str):
        if name == "fleet_status":
            return robot.fleet_status
        if name in ("list_alerts", "acknowledge_alert"):
            return getattr(self.alerts, name)
        return robot.tool(name)

    async def call_tool(self, name: str, arguments: dict[str, Any], context=None):
        if not self._slots.acquire(blocking=False):
            raise ToolError(f"busy: {MAX_CALLS} calls are already running; try again shortly")
        try:
            return await self._recorded(name, arguments, context)
        finally:
            self._slots.release()

    async def _recorded(self, name: str, arguments: dict[str, Any], context):
        call = Call(client_name(context), describe(name, arguments))
        audit = self.robot.audit
        t0 = time.perf_counter()
        await anyio.to_thread.run_sync(audit.start, call)  # a store that fails still serves
        token = CALL.set(call)
        try:
            result = await super().call_tool(name, arguments, context)
        except ToolError as exc:
            reason = reason_of(name, exc)
            await anyio.to_thread.run_sync(audit.finish, call, reason, t0, True)
            if call.unrecorded:
                reason = one_line(f"{reason}; {call.note()}", 500)
            raise ToolError(reason) from None
        finally:
            CALL.reset(token)
        text = ""
        if isinstance(result, CallToolResult):
            text = "\n".join(  # an image is kept as its kind, not its bytes
                c.text
                if isinstance(c, TextContent)
                else f"[{getattr(c, 'mime_type', c.type)} image]"
                for c in result.content
            )
        await anyio.to_thread.run_sync(audit.finish, call, text, t0, False)
        if call.unrecorded and isinstance(result, CallToolResult):
            # its own content item: a JSON answer's item stays JSON
            result.content = [*result.content, TextContent(type="text", text=call.note())]
        return result

    def _resources(self) -> None:
        gw = self.robot.gateway

        @self.resource("astiop://catalog", name="catalog", mime_type="application/json",
                       description="The robot's topics, services and actions with their types.")  # fmt: skip
        def catalog() -> str:
            c = gw.catalog
            return json.dumps({
                "topics": [{"name": t.name, "type": t.type, "rate_hz": t.rate_hz,
                            "description": t.description} for t in c.topics.values()],
                "services": [{"name": s.name, "type": s.type, "actuating": s.actuating,
                              "description": s.description} for s in c.services.values()],
                "actions": [{"name": a.name, "type": a.type, "description": a.description}
                            for a in c.actions.values()],
            }, indent=1)  # fmt: skip

        @self.resource("astiop://interfaces", name="interfaces", mime_type="text/plain",
                       description="`ros2 interface show` of every type in the catalog.")  # fmt: skip
        def interfaces() -> str:
            c = gw.catalog
            types = sorted({*(t.type for t in c.topics.values()),
                            *(s.type for s in c.services.values()),
                            *(a.type for a in c.actions.values())})  # fmt: skip
            parts = []
            for type_ in types:
                try:
                    parts.append(f"## {type_}\n{interface_show(type_)}")
                except InterfaceError:
                    parts.append(f"## {type_}\n(not known to astiop)\n")
            return "\n".join(parts)

        @self.resource(ALERTS_URI, name="alerts", mime_type="application/json",
                       description="The open alerts, newest first: subscribe to be told when "
                       "one opens or is acknowledged.")  # fmt: skip
        def alerts() -> str:
            return self.alerts.open_alerts()

        @self.resource("astiop://locations", name="locations", mime_type="application/json",
                       description="The named locations the robot can be sent to.")  # fmt: skip
        def locations() -> str:
            return json.dumps(self.robot.list_locations(), indent=1)


class BearerGate:
    """ASGI: every HTTP request must carry `Authorization: Bearer TOKEN`."""

    def __init__(self, app, token: str):
        self.app = app
        self.expected = f"Bearer {token}".encode()

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] == "http":
            given = dict(scope.get("headers") or []).get(b"authorization", b"")
            if not hmac.compare_digest(given, self.expected):
                body = b'{"error": "missing or wrong bearer token"}'
                await send({"type": "http.response.start", "status": 401, "headers": [
                    (b"content-type", b"application/json"), (b"www-authenticate", b"Bearer"),
                ]})  # fmt: skip
                await send({"type": "http.response.body", "body": body})
                return
        await self.app(scope, receive, send)


def serve_stdio(server: AstiopMCP) -> None:
    server.run("stdio")


def serve_http(server: AstiopMCP, host: str, port: int, token: str | None) -> None:
    import uvicorn

    app = server.streamable_http_app(host=host)
    served = BearerGate(app, token) if token else app
    logging.getLogger("uvicorn.error").setLevel(logging.WARNING)
    uvicorn.Server(uvicorn.Config(served, host=host, port=port, log_level="warning")).run()

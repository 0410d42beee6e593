"""Tool mode: the catalog as a closed list of choices the model picks from under a JSON schema.

The code, not the model, renders each choice into a `ros2` command line.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

from astiop.robot.catalog import Catalog

READABLE_EXCLUDED = {"/cmd_vel", "/tf", "/tf_static", "/plan"}
TRIGGER = "std_srvs/srv/Trigger"
GOTO_TYPE = "astiop_msgs/srv/GotoPosition"


@dataclass(frozen=True)
class Tool:
    id: str
    description: str
    command: str | None  # None: rendered from x, y, theta_deg


class ToolError(ValueError):
    pass


# Short names that echo operators' words: a small model picks by likeness to the request.
TOPIC_TOOLS = {
    "/battery_status": "battery",
    "/robot_pose": "where",
    "/robot_status": "status",
    "/obstacles": "obstacles",
    "/scan": "lidar",
    "/diagnostics": "diagnostics",
    "/conveyor/status": "conveyor",
    "/odom": "speed",
    "/plan": "path",
}
SERVICE_TOOLS = {
    "/stop": "stop",
    "/dock": "dock",
    "/undock": "undock",
    "/conveyor/load": "load",
    "/conveyor/unload": "unload",
}
COORDINATES = "drive_xy"


def build_tools(catalog: Catalog, locations: list[str]) -> list[Tool]:
    tools = [
        Tool(TOPIC_TOOLS.get(t.name, t.name), f"reads {t.name}", f"ros2 topic echo {t.name} --once")
        for t in catalog.topics.values()
        if t.name not in READABLE_EXCLUDED
    ]
    if "/robot_pose" in catalog.topics:  # both words operators use for it
        tools.append(Tool("position", "reads /robot_pose", "ros2 topic echo /robot_pose --once"))
    tools += [
        Tool(
            name,
            f"drives to {name}",
            f"ros2 service call /goto_position {GOTO_TYPE} \"{{name: '{name}'}}\"",
        )
        for name in locations
    ]
    if "/goto_position" in catalog.services:
        tools.append(Tool(COORDINATES, "drives to x, y in metres", None))
    tools += [
        Tool(
            SERVICE_TOOLS.get(s.name, s.name),
            f"calls {s.name}",
            f"ros2 service call {s.name} {TRIGGER}",
        )
        for s in catalog.services.values()
        if s.type == TRIGGER
    ]
    if "/list_locations" in catalog.services:
        tools.append(
            Tool(
                "locations",
                "calls /list_locations",
                "ros2 service call /list_locations astiop_msgs/srv/ListLocations",
            )
        )
    tools.append(Tool("none", "no robot command is needed", None))
    return tools


def _gbnf_literal(text: str) -> str:
    return json.dumps(json.dumps(text))


def tool_grammar(tools: list[Tool]) -> str:
    """GBNF for llama.cpp: the schema's language with no free whitespace, which small models
    otherwise fill until the token limit."""
    names = " | ".join(_gbnf_literal(t.id) for t in tools if t.id != COORDINATES)
    return (
        'root ::= "{\\"steps\\":[" step ("," step)? ("," step)? "]}"\n'
        'step ::= "{\\"tool\\":" name "}" | "{\\"tool\\":\\"drive_xy\\",\\"x\\":" '
        'num ",\\"y\\":" num "}"\n'
        f"name ::= {names}\n"
        'num ::= "-"? [0-9]{1,3} ("." [0-9]{1,3})?\n'
    )


def command_grammar() -> str:
    return (
        'root ::= "{\\"commands\\":[" cmd ("," cmd)? ("," cmd)? "]}"\n'
        'cmd ::= "\\"ros2 " char{1,200} "\\""\n'
        'char ::= [^"\\\\\\n] | "\\\\\\""\n'
    )


def tool_schema(tools: list[Tool]) -> dict:
    return {
        "type": "object",
        "properties": {
            "steps": {
                "type": "array",
                "minItems": 1,
                "maxItems": 3,
                "items": {
                    "type": "object",
                    "properties": {
                        "tool": {"enum": [t.id for t in tools]},
                        "x": {"type": "number"},
                        "y": {"type": "number"},
                        "theta_deg": {"type": "number"},
                    },
                    "required": ["tool"],
                },
            }
        },
        "required": ["steps"],
    }


def command_schema() -> dict:
    return {
        "type": "object",
        "properties": {
            "commands": {
                "type": "array",
                "maxItems": 3,
                "items": {"type": "string", "maxLength": 240},
            }
        },
        "required": ["commands"],
    }


def render(step: dict, tools: list[Tool]) -> str | None:
    """The command for one chosen step; None for 'none'."""
    if not isinstance(step, dict) or not isinstance(step.get("tool"), str):
        raise ToolError('each step must be an object like {"tool": "read /battery_status"}')
    by_id = {t.id: t for t in tools}
    tool = by_id.get(step["tool"].strip())
    if tool is None:
        raise ToolError(f"there is no tool '{step['tool']}'; pick one of the listed tools")
    if tool.id == "none":
        return None
    if tool.command is not None:
        return tool.command
    try:
        x, y = float(step["x"]), float(step["y"])
        theta = math.radians(float(step.get("theta_deg", 0.0)))
    except (KeyError, TypeError, ValueError):
        raise ToolError(f'"{COORDINATES}" needs numbers "x" and "y"') from None
    return (
        f"ros2 service call /goto_position {GOTO_TYPE} "
        f'"{{x: {x:.3f}, y: {y:.3f}, theta: {theta:.4f}}}"'
    )

"""Tool mode: the catalog as a closed list of choices the model picks from under a JSON schema.

The code, not the model, renders each choice into a `ros2` command line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from astiop.robot.catalog import Catalog

READABLE_EXCLUDED = {"/cmd_vel", "/tf", "/tf_static"}
TRIGGER = "std_srvs/srv/Trigger"
GOTO_TYPE = "astiop_msgs/srv/GotoPosition"


@dataclass(frozen=True)
class Tool:
    id: str
    description: str
    command: str | None  # None: rendered from x, y, theta_deg


class ToolError(ValueError):
    pass


def build_tools(catalog: Catalog, locations: list[str]) -> list[Tool]:
    tools = [
        Tool(f"read {t.name}", t.description, f"ros2 topic echo {t.name} --once")
        for t in catalog.topics.values()
        if t.name not in READABLE_EXCLUDED
    ]
    tools += [
        Tool(
            f"goto {name}",
            f"drive to the named location {name}",
            f"ros2 service call /goto_position {GOTO_TYPE} \"{{name: '{name}'}}\"",
        )
        for name in locations
    ]
    if "/goto_position" in catalog.services:
        tools.append(Tool("goto_xy", "drive to coordinates x, y (m), theta_deg", None))
    tools += [
        Tool(f"call {s.name}", s.description, f"ros2 service call {s.name} {TRIGGER}")
        for s in catalog.services.values()
        if s.type == TRIGGER
    ]
    if "/list_locations" in catalog.services:
        tools.append(
            Tool(
                "list_locations",
                "names and poses of the named locations",
                "ros2 service call /list_locations astiop_msgs/srv/ListLocations",
            )
        )
    tools.append(Tool("none", "no robot command is needed", None))
    return tools


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
        raise ToolError('goto_xy needs numbers "x" and "y"') from None
    return (
        f"ros2 service call /goto_position {GOTO_TYPE} "
        f'"{{x: {x:.3f}, y: {y:.3f}, theta: {theta:.4f}}}"'
    )


def tool_lines(tools: list[Tool]) -> str:
    return "\n".join(f"- {t.id}: {t.description}" for t in tools)

"""Tool mode: the catalog as a closed list of choices the model picks from under a JSON schema.

The code, not the model, renders each choice into a `ros2` command line.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass

from astiop.agent import rules
from astiop.agent.intent import SERVICE_FOR, Intent, Motion
from astiop.agent.roles import KEY_ROLES
from astiop.agent.rules import command_for
from astiop.ros2.catalog import RELEASE, Catalog
from astiop.ros2.render import GOTO_TYPE, goto_command, nav_goal_command
from astiop.ros2.roles import ROLES

READABLE_EXCLUDED = {"/cmd_vel", "/tf", "/tf_static", "/plan"}
# The operator's own: never in the model's prompt or tools (releasing a held robot is a person's
# decision, as the console's ctrl+r is).
OPERATOR_ONLY = {RELEASE}
TRIGGER = "std_srvs/srv/Trigger"


@dataclass(frozen=True)
class Tool:
    id: str
    description: str
    command: str | None  # None: rendered from the step's own fields
    kind: str = "read"  # what it does, as the request's intent names it (astiop.agent.intent)
    action: str = ""  # drive_xy on a Nav2 robot: its NavigateToPose action


class ToolError(ValueError):
    pass


# Short names that echo operators' words (a small model picks by likeness to the request), by the
# ASTIbot's topic and by role whatever the robot calls it: each role's `tool` (astiop.ros2.roles)
TOPIC_TOOLS = {r.key: r.tool for r in ROLES if r.tool}
ROLE_TOOLS = {r.name: r.tool for r in ROLES if r.tool}
UNREADABLE_ROLES = tuple(r.name for r in ROLES if not r.readable)  # commands, or too big
SERVICE_TOOLS = {
    "/stop": "stop",
    "/dock": "dock",
    "/undock": "undock",
    "/conveyor/load": "load",
    "/conveyor/unload": "unload",
}
SERVICE_KINDS = {service: kind for kind, service in SERVICE_FOR.items()}
COORDINATES = "drive_xy"
SAVE = "save_here"
# short bounded moves, rendered like the rules render them (always inside the safety clamp)
MOTION_TOOLS = {
    "forward": Motion(vx=0.3),
    "backward": Motion(vx=-0.3),
    "strafe_left": Motion(vy=0.3),
    "strafe_right": Motion(vy=-0.3),
    "turn_left": Motion(wz=0.6),
    "turn_right": Motion(wz=-0.6),
}


def build_tools(catalog: Catalog, locations: list[str]) -> list[Tool]:
    """The model's choices on this robot: its readings by role, its places, its services, its
    motions; in the names of its profile (the ASTIbot's own without one)."""
    profile = catalog.profile
    ns = profile.namespace if profile else ""

    def local(name: str) -> str:  # the ASTIbot's names, compared inside its namespace
        return name[len(ns) :] if ns and name.startswith(ns + "/") else name

    role_of = {m.name: r for r, m in profile.matches.items() if m.name} if profile else {}
    skip = READABLE_EXCLUDED | {profile.name(r) for r in UNREADABLE_ROLES if profile} - {None}
    tools = [
        Tool(
            ROLE_TOOLS.get(role_of.get(t.name, ""), TOPIC_TOOLS.get(local(t.name), t.name)),
            f"reads {t.name}",
            f"ros2 topic echo {t.name} --once",
        )
        for t in catalog.topics.values()
        if t.name not in skip
        and local(t.name) not in skip
        and (t.name in role_of or not profile or profile.make == "astibot")
    ]
    pose = profile.name("pose") if profile else "/robot_pose"
    if pose in catalog.topics:  # both words operators use for it
        tools.append(Tool("position", f"reads {pose}", f"ros2 topic echo {pose} --once"))
    action = rules.nav_action(profile)
    tools += [
        Tool(name, f"drives to {name}", goto_command(name), "navigate")
        for name in (locations if not action else [])
    ]
    goto = profile.name("navigation") if profile else "/goto_position"
    if goto in catalog.services or action:
        tools.append(Tool(COORDINATES, "drives to x, y in metres", None, "navigate", action or ""))
    tools += [
        Tool(
            SERVICE_TOOLS.get(local(s.name), s.name),
            f"calls {s.name}",
            f"ros2 service call {s.name} {TRIGGER}",
            SERVICE_KINDS.get(local(s.name), "other"),
        )
        for s in catalog.services.values()
        if s.type == TRIGGER and local(s.name) not in OPERATOR_ONLY
    ]
    velocity = profile.name("velocity_command") if profile else "/cmd_vel"
    if velocity in catalog.topics:
        tools += [
            Tool(
                name,
                f"moves the robot ({name.replace('_', ' ')}) for 2 s",
                _motion(m, profile),
                "motion",
            )
            for name, m in MOTION_TOOLS.items()
            if not m.vy or not action  # a Nav2 base (differential drive) does not strafe
        ]
    if ns + "/save_location" in catalog.services:
        tools.append(Tool(SAVE, "saves the robot's pose under a new name", None, "save"))
    if ns + "/list_locations" in catalog.services:
        tools.append(
            Tool(
                "locations",
                "calls /list_locations",
                "ros2 service call /list_locations astiop_msgs/srv/ListLocations",
                "list",
            )
        )
    tools.append(Tool("none", "no robot command is needed", None, "none"))
    return tools


def narrow(tools: list[Tool], intents: list[Intent]) -> list[Tool]:
    """The tools that can do what the request asks, when every clause's intent is known:
    a question gets the reads (of its topics, when each names one), a stop the stop, a trip
    the places. The model still picks which; the gate checks the pick."""
    kinds = {i.kind for i in intents}
    if not kinds or kinds & {"unknown", "none"}:
        return tools
    kept = [t for t in tools if t.kind in kinds]
    reads = [i.topic for i in intents if i.kind == "read"]
    if reads and all(reads):  # every question names what it asks about: only those reads
        echoes = {f"ros2 topic echo {topic} --once" for topic in reads}
        echoes |= {
            t.command
            for t in tools
            if t.id in {ROLE_TOOLS.get(KEY_ROLES.get(k, "")) for k in reads}
        }
        on_topic = [t for t in kept if t.kind != "read" or t.command in echoes]
        if any(t.kind == "read" for t in on_topic):
            kept = on_topic
    return kept or tools


def _motion(m: Motion, profile=None) -> str:
    command = command_for(Intent("motion", motion=m), profile)
    assert command is not None
    return command


def _gbnf_literal(text: str) -> str:
    return json.dumps(json.dumps(text))


def tool_grammar(tools: list[Tool]) -> str:
    """GBNF for llama.cpp: the schema's language with no free whitespace, which small models
    otherwise fill until the token limit. Only the offered tools can be written."""
    ids = {t.id for t in tools}
    steps = []
    names = " | ".join(_gbnf_literal(t.id) for t in tools if t.id not in (COORDINATES, SAVE))
    if names:
        steps.append('"{\\"tool\\":" name "}"')
    if COORDINATES in ids:
        steps.append('"{\\"tool\\":\\"drive_xy\\",\\"x\\":" num ",\\"y\\":" num "}"')
    if SAVE in ids:
        steps.append('"{\\"tool\\":\\"save_here\\",\\"name\\":\\"" [a-z0-9_]{1,32} "\\"}"')
    grammar = 'root ::= "{\\"steps\\":[" step ("," step)? ("," step)? "]}"\n'
    grammar += f"step ::= {' | '.join(steps)}\n"
    if names:
        grammar += f"name ::= {names}\n"
    return grammar + 'num ::= "-"? [0-9]{1,3} ("." [0-9]{1,3})?\n'


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
                        "name": {"type": "string", "pattern": "^[a-z0-9_]{1,32}$"},
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
    if tool.id == SAVE:
        name = step.get("name")
        if not isinstance(name, str) or not re.fullmatch(r"[a-z0-9_]{1,32}", name):
            raise ToolError(f'"{SAVE}" needs a "name" of lower-case letters, digits and _')
        command = command_for(Intent("save", place=name))
        assert command is not None
        return command
    try:
        x, y = float(step["x"]), float(step["y"])
        theta = math.radians(float(step.get("theta_deg", 0.0)))
    except (KeyError, TypeError, ValueError, OverflowError):
        raise ToolError(f'"{COORDINATES}" needs numbers "x" and "y"') from None
    if not all(math.isfinite(v) for v in (x, y, theta)):
        raise ToolError(f'"{COORDINATES}" needs finite numbers')
    if tool.action:
        return nav_goal_command(tool.action, x, y, theta)
    return (
        f"ros2 service call /goto_position {GOTO_TYPE} "
        f'"{{x: {x:.3f}, y: {y:.3f}, theta: {theta:.4f}}}"'
    )

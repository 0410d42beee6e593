"""The rule-based planner: no LLM at all. The deterministic baseline ("traditional approaches"
in the paper) and the fallback when no model answers. Labelled `rules` everywhere.

It plans from the request's intent (`astiop.agent.intent`) and plans nothing rather than guess
an actuation.
"""

from __future__ import annotations

from astiop.agent.grounding import factual_answer
from astiop.agent.intent import SERVICE_FOR, Intent, classify
from astiop.robot.backend import Execution

GOTO = "ros2 service call /goto_position astiop_msgs/srv/GotoPosition"
TRIGGER = "std_srvs/srv/Trigger"
TWIST = "geometry_msgs/msg/Twist"
PUBLISH_HZ = 10
UNKNOWN = "[rules] I don't know how to do that"


def command_for(intent: Intent) -> str | None:
    kind = intent.kind
    if kind == "read":
        return f"ros2 topic echo {intent.topic} --once" if intent.topic else None
    if kind == "list":
        return "ros2 service call /list_locations astiop_msgs/srv/ListLocations"
    if kind in SERVICE_FOR:
        return f"ros2 service call {SERVICE_FOR[kind]} {TRIGGER}"
    if kind == "navigate" and intent.xy is not None:
        x, y = intent.xy
        return f'{GOTO} "{{x: {x:.3f}, y: {y:.3f}, theta: {intent.theta or 0.0:.4f}}}"'
    if kind == "navigate" and intent.place:
        return f"{GOTO} \"{{name: '{intent.place}'}}\""
    if kind == "save" and intent.place:
        return (
            "ros2 service call /save_location astiop_msgs/srv/SaveLocation "
            f"\"{{name: '{intent.place}', description: 'saved by the operator'}}\""
        )
    if kind == "configure" and intent.place and intent.xy:
        return f"ros2 param set /astibot_base {intent.place} {intent.xy[0]:g}"
    if kind == "motion" and intent.motion is not None:
        m = intent.motion
        times = max(1, round(m.seconds * PUBLISH_HZ))
        return (
            f"ros2 topic pub -t {times} -r {PUBLISH_HZ} /cmd_vel {TWIST} "
            f'"{{linear: {{x: {m.vx:g}, y: {m.vy:g}, z: 0.0}}, '
            f'angular: {{x: 0.0, y: 0.0, z: {m.wz:.3g}}}}}"'
        )
    return None


def plan(request: str, locations: list[str]) -> list[str]:
    return plan_intents(classify(request, locations))


def plan_intents(intents: list[Intent]) -> list[str]:
    """The commands for a request already classified (an agent turn classifies it once)."""
    commands: list[str] = []
    for intent in intents:
        command = command_for(intent)
        if command and command not in commands:
            commands.append(command)
    return commands[:3]


def interpret(request: str, executions: list[Execution], waited: list[str] | None = None) -> str:
    if not executions:
        return (
            f"{UNKNOWN}. I understand requests about the robot's position, speed, battery, "
            "status, obstacles, lidar, diagnostics and conveyor, and requests to go to a "
            "location or coordinates, move a little, dock, undock, load, unload, save or list "
            "locations, and stop."
        )
    return "[rules] " + factual_answer(executions, waited=waited or ())

"""The rule-based planner: no LLM at all. The deterministic baseline ("traditional approaches"
in the paper) and the fallback when no model answers. Labelled `rules` everywhere.

It plans from the request's intent (`astiop.agent.intent`) and plans nothing rather than guess
an actuation.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from astiop.agent.grounding import factual_answer
from astiop.agent.intent import SERVICE_FOR, Intent, classify
from astiop.agent.roles import name_for
from astiop.ros2.render import goal_pose_command, nav_goal_command, velocity_pub_command
from astiop.ros2.validation import CANCEL_SUFFIX
from astiop.transports.base import Execution

Locate = Callable[[str], "tuple[float, float] | None"]

GOTO = "ros2 service call /goto_position astiop_msgs/srv/GotoPosition"
TRIGGER = "std_srvs/srv/Trigger"
TWIST = "geometry_msgs/msg/Twist"
PUBLISH_HZ = 10
UNKNOWN = "[rules] I don't know how to do that"


def command_for(intent: Intent, profile: Any = None, locate: Locate | None = None) -> str | None:
    """The command for one intent, in the names of the robot's `profile` (the ASTIbot's without
    one); None when the robot has nothing that does it."""
    foreign = profile is not None and profile.kind("navigation") in ("action", "topic")
    if foreign or (profile is not None and not profile.has("stop")):
        other = _other_robot(intent, profile, locate)
        if other is not False:
            return other
    kind = intent.kind
    if kind == "read":
        name = name_for(intent.topic, profile) if intent.topic else None
        return f"ros2 topic echo {name} --once" if name else None
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


def nav_action(profile: Any) -> str | None:
    """The robot's NavigateToPose action, where that is how it navigates (Nav2)."""
    if profile is None or profile.kind("navigation") != "action":
        return None
    return profile.name("navigation")


def _other_robot(intent: Intent, profile: Any, locate: Locate | None) -> str | None | bool:
    """What differs on a robot that is not the ASTIbot (a TurtleBot3 under Nav2): goals by
    NavigateToPose, a stop by a zero velocity, motion on its own velocity topic and type;
    None: the robot has nothing that does it; False: as on the ASTIbot."""
    action, kind = nav_action(profile), intent.kind
    goal_topic = profile.name("navigation") if profile.kind("navigation") == "topic" else None
    if kind == "navigate" and (action or goal_topic):
        xy = intent.xy or (locate(intent.place) if intent.place and locate else None)
        if xy is None:
            return None
        if goal_topic:  # a navigator that takes its goals on a topic (/goal_pose)
            return goal_pose_command(goal_topic, xy[0], xy[1], intent.theta or 0.0)
        return nav_goal_command(action, xy[0], xy[1], intent.theta or 0.0)
    velocity = profile.name("velocity_command")
    if kind in SERVICE_FOR and not profile.has(kind):
        if kind == "stop" and action:  # no stop service: Nav2 drives on after a zero Twist
            return f'ros2 service call {action}{CANCEL_SUFFIX} action_msgs/srv/CancelGoal "{{}}"'
        if kind == "stop" and velocity:
            return _zero_velocity(profile)
        return None
    if kind == "motion" and intent.motion is not None and velocity:
        m = intent.motion
        times = max(1, round(m.seconds * PUBLISH_HZ))
        return _publish(profile, velocity, f"-t {times} -r {PUBLISH_HZ}", m.vx, m.vy, m.wz)
    return False


def _zero_velocity(profile: Any) -> str | None:
    velocity = profile.name("velocity_command")
    return _publish(profile, velocity, "--once", 0.0, 0.0, 0.0) if velocity else None


def _publish(profile: Any, name: str, how: str, vx: float, vy: float, wz: float) -> str:
    """A velocity in the robot's own type."""
    typ = profile.matches["velocity_command"].type
    return velocity_pub_command(name, typ, how, vx, vy, wz)


def plan(request: str, locations: list[str]) -> list[str]:
    return plan_intents(classify(request, locations))


def plan_intents(
    intents: list[Intent], profile: Any = None, locate: Locate | None = None
) -> list[str]:
    """The commands for a request already classified (an agent turn classifies it once), in
    the names of the robot's `profile`; `locate`: a named place's (x, y)."""
    commands: list[str] = []
    for intent in intents:
        command = command_for(intent, profile, locate)
        also = [] if command is None else [command]
        if intent.kind == "stop" and command and CANCEL_SUFFIX in command:
            also.append(_zero_velocity(profile))  # its goals cancelled, then held still
        commands += [c for c in also if c and c not in commands]
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

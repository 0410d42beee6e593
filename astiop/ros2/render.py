"""The command line that is actually sent, rebuilt from the checked command, not the typed words.

Values come from the checked message (after safety's clamp), the type is always present, and
names are the full names the catalog knows.
"""

from __future__ import annotations

import math
import shlex

import yaml

from astiop.ros2.grammar import verb_parser
from astiop.ros2.validation import Checked

GOTO_TYPE = "astiop_msgs/srv/GotoPosition"


def goto_command(name: str) -> str:
    """The command that sends the robot to a named location (console, agent, `record --goto`)."""
    return f"ros2 service call /goto_position {GOTO_TYPE} \"{{name: '{name}'}}\""


NAVIGATE_TO_POSE = "nav2_msgs/action/NavigateToPose"


def nav_goal_command(action: str, x: float, y: float, theta: float) -> str:
    """A NavigateToPose goal in the map frame (Nav2's), the heading as a unit quaternion."""
    half = theta / 2
    return (
        f'ros2 action send_goal {action} {NAVIGATE_TO_POSE} "{{pose: {{header: '
        f"{{frame_id: map}}, pose: {{position: {{x: {x:.3f}, y: {y:.3f}}}, "
        f'orientation: {{z: {math.sin(half):.4f}, w: {math.cos(half):.4f}}}}}}}}}"'
    )


POSE_STAMPED = "geometry_msgs/msg/PoseStamped"


def goal_pose_command(topic: str, x: float, y: float, theta: float) -> str:
    """A goal published on a navigator's goal topic (Nav2's /goal_pose), in the map frame."""
    half = theta / 2
    return (
        f'ros2 topic pub --once {topic} {POSE_STAMPED} "{{header: {{frame_id: map}}, pose: '
        f"{{position: {{x: {x:.3f}, y: {y:.3f}}}, orientation: {{z: {math.sin(half):.4f}, "
        f'w: {math.cos(half):.4f}}}}}}}"'
    )


def velocity_pub_command(name: str, type_: str, how: str, vx: float, vy: float, wz: float) -> str:
    """`ros2 topic pub HOW NAME TYPE` of a velocity (a TwistStamped: its twist)."""
    twist = (
        f"{{linear: {{x: {vx:g}, y: {vy:g}, z: 0.0}}, angular: {{x: 0.0, y: 0.0, z: {wz:.3g}}}}}"
    )
    body = f"{{twist: {twist}}}" if type_ == "geometry_msgs/msg/TwistStamped" else twist
    return f'ros2 topic pub {how} {name} {type_} "{body}"'


def flow_yaml(message: dict) -> str:
    return yaml.safe_dump(message, default_flow_style=True, width=100_000, sort_keys=False).strip()


def sent_argv(checked: Checked) -> list[str]:
    """What follows `ros2` on the command line for this checked command."""
    cmd = checked.command
    if cmd is None:
        raise ValueError(f"'{checked.text}' was not read as a command: nothing to send")
    name, type_, message = cmd.name or "", checked.type or "", checked.message or {}
    key = cmd.key
    if key == ("topic", "pub"):
        argv = ["topic", "pub"]
        if "once" in cmd.flags:
            argv.append("--once")
        else:
            argv += ["-t", str(cmd.options["times"])]
        if "rate" in cmd.options:
            argv += ["-r", f"{cmd.options['rate']:g}"]
        return [
            *argv,
            name,
            type_,
            flow_yaml(stamped_now(type_, message)),
        ]
    if key == ("service", "call"):
        return ["service", "call", name, type_, flow_yaml(message)]
    if key == ("action", "send_goal"):
        argv = ["action", "send_goal", name, type_, flow_yaml(message)]
        return argv + (["--feedback"] if "feedback" in cmd.flags else [])
    if key == ("param", "set"):
        return ["param", "set", cmd.args["node"], cmd.args["param"], repr(message["value"])]
    if key == ("param", "get"):
        return ["param", "get", cmd.args["node"], cmd.args["param"]]
    return _full_names(cmd)


def _full_names(cmd) -> list[str]:
    """The typed words with the name as the catalog knows it (`navigator` -> `/navigator`):
    real ros2 matches node names exactly."""
    argv = list(cmd.argv)
    options = verb_parser(cmd.distro, cmd.key)._option_string_actions
    typed, value_next = [], False
    for i, word in enumerate(argv[2:], 2):
        if value_next:  # an option's value (`-w 5`), not a name
            value_next = False
        elif word.startswith("-"):
            action = options.get(word)
            value_next = action is not None and action.nargs != 0
        else:
            typed.append(i)
    if cmd.name and typed:
        argv[typed[0]] = cmd.name
    elif cmd.args.get("node") and typed:
        argv[typed[0]] = cmd.args["node"]
    return argv


def shell_word(word: str) -> str:
    """`word` quoted for a POSIX shell as a person reads it best: in double quotes when it holds
    a single quote and nothing a shell expands there (YAML's `''`), else as `shlex` quotes."""
    if "'" in word and not any(c in word for c in '"$`\\!'):
        return f'"{word}"'
    return shlex.quote(word)


def sent_text(checked: Checked) -> str:
    """The command as sent, to be read (and pasted into a shell) by the person approving it."""
    return "ros2 " + " ".join(shell_word(word) for word in sent_argv(checked))


def zero_twist() -> dict:
    return {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}


STAMPED = "geometry_msgs/msg/TwistStamped"


def velocity_message(type_: str, twist: dict) -> dict:
    """A Twist as the robot's /cmd_vel type wants it (Jazzy's diff_drive wants TwistStamped)."""
    return {"header": {"frame_id": "base_link"}, "twist": twist} if type_ == STAMPED else twist


def stamped_now(type_: str, message: dict) -> dict:
    """`header: auto` makes ros2 topic pub stamp each message now (humble and jazzy; see
    ros2topic/verb/pub.py, expand_header_auto): a zero stamp looks stale to a controller."""
    if type_ == STAMPED and isinstance(message.get("header"), dict):
        return {**message, "header": "auto"}
    return message

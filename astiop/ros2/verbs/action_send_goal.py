"""`ros2 action send_goal` (ros2action/verb/send_goal.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import values_or_stdin
from astiop.ros2.verbs.base import GOAL, Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("action_name")
    p.add_argument("action_type")
    values_or_stdin(p, distro, "goal", required_on_humble=True)
    p.add_argument("-f", "--feedback", action="store_true")


def check(cmd, catalog):
    from astiop.ros2.interfaces import fill
    from astiop.ros2.verbs.checks import Checked, action_spec, check_type

    spec = action_spec(cmd, catalog)
    check_type(cmd.args["type"], spec.type, spec.name)
    msg = fill(spec.type, cmd.args.get("values"), part=0)
    notes: tuple[str, ...] = ()
    header = msg.get("pose", {}).get("header") if isinstance(msg.get("pose"), dict) else None
    if header is not None and not header.get("frame_id"):
        header["frame_id"] = "map"  # Nav2 cannot transform a goal with no frame
        notes = ("the goal's header.frame_id was empty: set to map",)
    return Checked(cmd.text, cmd, True, "", "actuate", spec.type, msg, notes)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    return t.send_goal(c, timeout)


VERB = Verb(
    ("action", "send_goal"),
    arguments,
    run,
    check,
    runs_as=GOAL,
    example="ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
    '"{pose: {header: {frame_id: map}, pose: {position: {x: 5.0, y: 3.0}}}}" --feedback',
    values_from="goal",
)

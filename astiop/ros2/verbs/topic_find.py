"""`ros2 topic find` (ros2topic/verb/find.py, humble and jazzy alike): the topics of one type."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    strategy(p)
    p.add_argument("type", metavar="topic_type")
    p.add_argument("-c", "--count-topics", action="store_true")
    p.add_argument("--include-hidden-topics", action="store_true")


def run(t: Transport, c: Checked, timeout: float) -> Output:
    wanted = c.parsed.args["type"]
    names = [name for name, types in t.graph("topic") if wanted in types.split(", ")]
    if "count_topics" in c.parsed.flags:
        return f"{len(names)}\n", names
    return "".join(f"{n}\n" for n in names), names


VERB = Verb(("topic", "find"), arguments, run, example="ros2 topic find sensor_msgs/msg/LaserScan")

"""`ros2 topic find` (ros2topic/verb/find.py, humble and jazzy alike): the topics of one type."""

from __future__ import annotations

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Verb


def arguments(p, distro: str) -> None:
    strategy(p)
    p.add_argument("type", metavar="topic_type")
    p.add_argument("-c", "--count-topics", action="store_true")
    p.add_argument("--include-hidden-topics", action="store_true")


def run(t, c, timeout: float):
    wanted = c.command.args["type"]
    names = [name for name, types in t.graph("topic") if wanted in types.split(", ")]
    if "count_topics" in c.command.flags:
        return f"{len(names)}\n", names
    return "".join(f"{n}\n" for n in names), names


VERB = Verb(("topic", "find"), arguments, run, example="ros2 topic find sensor_msgs/msg/LaserScan")

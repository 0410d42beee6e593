"""`ros2 topic info` (ros2topic/verb/info.py)."""

from __future__ import annotations

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Verb


def arguments(p, distro: str) -> None:
    p.add_argument("topic_name")
    p.add_argument("--verbose", "-v", action="store_true")
    strategy(p)


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import checked_topic

    return checked_topic(cmd, catalog)


def run(t, c, timeout: float):
    pubs, subs = t.endpoint_counts(c.command.name)
    text = f"Type: {c.type}\nPublisher count: {pubs}\nSubscription count: {subs}\n"
    return text, {"type": c.type, "publishers": pubs, "subscribers": subs}


VERB = Verb(("topic", "info"), arguments, run, check)

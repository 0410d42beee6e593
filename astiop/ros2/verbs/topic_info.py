"""`ros2 topic info` (ros2topic/verb/info.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import strategy
from astiop.ros2.verbs.base import Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


def arguments(p, distro: str) -> None:
    p.add_argument("topic_name")
    p.add_argument("--verbose", "-v", action="store_true")
    strategy(p)


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import checked_topic

    return checked_topic(cmd, catalog)


def run(t: Transport, c: Checked, timeout: float) -> Output:
    pubs, subs = t.endpoint_counts(c.named)
    text = f"Type: {c.interface}\nPublisher count: {pubs}\nSubscription count: {subs}\n"
    return text, {"type": c.interface, "publishers": pubs, "subscribers": subs}


VERB = Verb(("topic", "info"), arguments, run, check)

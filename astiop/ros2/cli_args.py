"""ros2cli's argument parsers for the verbs astiop uses, per distro: astiop's grammar, and the
emulated `ros2`'s. Each verb's arguments are in its module (`verbs/topic_hz.py`, read from
ros2/ros2cli's `humble` and `jazzy` branches, ros2topic/verb/hz.py); the daemon's here
(ros2cli/verb/daemon). Stdlib only: this runs at every emulated `ros2` call.
"""

from __future__ import annotations

import argparse

from astiop.distro import DISTROS  # noqa: F401 - the emulated ros2 reads it here
from astiop.ros2.verbs import VERBS


def build_parser(distro: str, parser_class=argparse.ArgumentParser) -> argparse.ArgumentParser:
    root = parser_class(prog="ros2")
    nouns = root.add_subparsers(dest="command", required=True)
    subs: dict[str, argparse._SubParsersAction] = {}
    for (noun, sub), verb in VERBS.items():
        if noun not in subs:
            subs[noun] = nouns.add_parser(noun).add_subparsers(dest="verb", required=True)
        verb.arguments(subs[noun].add_parser(sub), distro)
    daemon = nouns.add_parser("daemon").add_subparsers(dest="verb", required=True)
    for sub in ("start", "stop", "status"):
        daemon.add_parser(sub)
    return root

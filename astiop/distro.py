"""Which ROS 2 distro's grammar and messages astiop speaks: the environment's ROS_DISTRO where
it is one astiop knows, else Jazzy. Stdlib only: the simulator and the vocabulary both read it."""

from __future__ import annotations

import os

DISTROS = ("humble", "jazzy")


def current_distro() -> str:
    distro = os.environ.get("ROS_DISTRO", "").strip().lower()
    return distro if distro in DISTROS else "jazzy"

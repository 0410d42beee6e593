"""What a command's result says of itself once it ran: how it is known (measured, commanded,
accepted, reported), the role its name plays on the robot, and a reading's period and age."""

from __future__ import annotations

from astiop.ros2.catalog import Catalog
from astiop.ros2.command import Ros2Command
from astiop.ros2.profile_types import Profile
from astiop.ros2.roles import ROLE_BY_NAME
from astiop.ros2.verbs import VERBS
from astiop.transports.base import Execution

MAX_STAMP_AGE_S = 86400.0  # a stamp older than a day is on another clock, not a day-old reading


def provenance(cmd: Ros2Command, kind: str, catalog: Catalog) -> str:
    if VERBS[cmd.key].measures:
        return "measured"
    if cmd.command == "service" and cmd.verb == "call":
        spec = catalog.services.get(cmd.name) if cmd.name is not None else None
        return "accepted" if spec is not None and spec.starts_job else "reported"
    return "commanded" if kind == "actuate" else "reported"


def name_role(name: str | None, result: Execution, profile: Profile) -> None:
    """The role the command's name plays on the robot, and a battery's units: what it read
    is then said as a battery, a pose, whatever the robot calls it."""
    result.role = next((r for r, m in profile.matches.items() if name and m.name == name), "")
    if result.role == "battery":
        result.units = profile.units.battery_percentage
    role = ROLE_BY_NAME.get(result.role)
    for field in role.sized if role is not None else ():
        # read as its size, not its content (an image's megabytes of pixels in the store)
        data = result.values.get(field) if isinstance(result.values, dict) else None
        if isinstance(data, list | tuple | bytes | str):
            kept = {k: v for k, v in result.values.items() if k != field}
            result.values = {**kept, f"{field}_bytes": len(data)}


def date_reading(topic: str | None, result: Execution, catalog: Catalog, now: float | None) -> None:
    """A reading's period and its age by its header stamp, when the robot's clock (`now`) is
    known here and agrees with the stamp (a stamp on another clock, e.g. sim time, says
    nothing)."""
    spec = catalog.topics.get(topic) if topic is not None else None
    if spec is not None and spec.rate_hz > 0:
        result.period_s = 1.0 / spec.rate_hz
    header = result.values.get("header") if isinstance(result.values, dict) else None
    stamp = header.get("stamp") if isinstance(header, dict) else None
    if now is None or not isinstance(stamp, dict):
        return
    try:
        age = now - (int(stamp["sec"]) + int(stamp["nanosec"]) * 1e-9)
    except (KeyError, TypeError, ValueError):
        return
    if -1.0 <= age <= MAX_STAMP_AGE_S:
        result.age_s = max(age, 0.0)

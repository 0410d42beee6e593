"""Profile files: TOML, one per robot, fixing what matching on the graph cannot know (a dock
service with an unusual name, a battery reported 0-100, the robot's own speed limits); the
profiles astiop ships (astibot, turtlebot3_burger, turtlebot3_waffle) are files of the same
form in ros2/profiles/."""

from __future__ import annotations

import functools
import math
import re
from dataclasses import replace
from importlib import resources
from pathlib import Path
from typing import Any

from astiop.ros2.profile_types import (
    Limits,
    MapSpec,
    Profile,
    ProfileSpec,
    Units,
    normalise_namespace,
)
from astiop.ros2.roles import ROLE_NAMES

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the Jetson's ROS 2 Humble
    import tomli as tomllib  # type: ignore[no-redef]

SECTIONS = ("robot", "roles", "units", "limits", "map")
MAP_NAME_RE = re.compile(r"^[A-Za-z0-9_.-]{1,64}$")
PERCENTAGE = ("fraction", "percent")


class ProfileError(ValueError):
    """A profile file that cannot be used, said in one line."""


@functools.cache
def shipped_names() -> tuple[str, ...]:
    folder = resources.files("astiop.ros2") / "profiles"
    return tuple(sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")))


@functools.cache
def shipped(make: str) -> ProfileSpec | None:
    """The profile astiop ships for `make`, or None."""
    if make not in shipped_names():
        return None
    text = (resources.files("astiop.ros2") / "profiles" / f"{make}.toml").read_text("utf-8")
    return parse(text, f"the shipped {make} profile")


def read_spec(setting: str, namespace: str = "") -> ProfileSpec:
    """`robot.profile` as set: "auto" (matched on the graph), a shipped profile's name, or a
    file's path; `namespace` (robot.namespace, --namespace) wins over the file's."""
    try:
        ns = normalise_namespace(namespace)
    except ValueError as exc:
        raise ProfileError(str(exc)) from None
    if setting in ("", "auto"):
        spec = ProfileSpec()
    elif (found := shipped(setting) if setting in shipped_names() else None) is not None:
        spec = found
    else:
        path = Path(setting).expanduser()
        if not path.is_file():
            names = ", ".join(shipped_names())
            raise ProfileError(f"no profile file {path} (or a shipped profile: auto, {names})")
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise ProfileError(f"cannot read {path}: {exc.strerror}") from None
        spec = parse(text, str(path))
    if ns or not spec.namespace:
        spec = replace(spec, namespace=ns)
    return spec


def parse(text: str, source: str) -> ProfileSpec:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ProfileError(f"{source}: not TOML ({exc})") from None
    unknown = sorted(set(data) - set(SECTIONS))
    if unknown:
        raise ProfileError(
            f"{source}: unknown section [{unknown[0]}] (known: {', '.join(SECTIONS)})"
        )
    robot = _table(data, "robot", source, {"make": str, "namespace": str})
    roles = _table(data, "roles", source, dict.fromkeys(ROLE_NAMES, str))
    for role, name in roles.items():
        if name and not name.startswith("/"):
            raise ProfileError(f"{source}: roles.{role} = {name!r}: a name starts with /")
    units = _table(data, "units", source, {"battery_percentage": str})
    pct = units.get("battery_percentage")
    if pct is not None and pct not in PERCENTAGE:
        raise ProfileError(
            f"{source}: units.battery_percentage is fraction or percent, not {pct!r}"
        )
    limits = _table(data, "limits", source, dict.fromkeys(Limits.__dataclass_fields__, float))
    if limits.get("battery_low", 0) >= 100:
        raise ProfileError(f"{source}: limits.battery_low is a percentage below 100")
    try:
        ns = normalise_namespace(robot.get("namespace", ""))
    except ValueError as exc:
        raise ProfileError(f"{source}: {exc}") from None
    where = _map_table(data, source)
    return ProfileSpec(
        robot.get("make", ""), ns, roles, Units(pct), Limits(**limits), source, where
    )


def _map_table(data: dict, source: str) -> MapSpec:
    """[map]: name (the robot's places belong to it), geofence [x_min, y_min, x_max, y_max]."""
    table = data.get("map", {})
    if not isinstance(table, dict):
        raise ProfileError(f"{source}: [map] is a table")
    unknown = sorted(set(table) - {"name", "geofence"})
    if unknown:
        raise ProfileError(f"{source}: unknown key map.{unknown[0]} (known: name, geofence)")
    name = table.get("name", "")
    if not isinstance(name, str) or (name and not MAP_NAME_RE.match(name)):
        raise ProfileError(f"{source}: map.name is 1-64 letters, digits, '_', '-' or '.'")
    fence = table.get("geofence")
    if fence is None:
        return MapSpec(name)
    numbers = isinstance(fence, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in fence
    )
    if not numbers or len(fence) != 4 or fence[2] <= fence[0] or fence[3] <= fence[1]:
        raise ProfileError(
            f"{source}: map.geofence is [x_min, y_min, x_max, y_max] in metres, min below max"
        )
    x_min, y_min, x_max, y_max = (float(v) for v in fence)
    return MapSpec(name, (x_min, y_min, x_max, y_max))


def _table(data: dict, section: str, source: str, keys: dict[str, type]) -> dict[str, Any]:
    table = data.get(section, {})
    if not isinstance(table, dict):
        raise ProfileError(f"{source}: [{section}] is a table")
    out = {}
    for key, value in table.items():
        if key not in keys:
            raise ProfileError(f"{source}: unknown key {section}.{key} (known: {', '.join(keys)})")
        want = keys[key]
        if want is float:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ProfileError(f"{source}: {section}.{key} is a number")
            value = float(value)
            if not math.isfinite(value) or value <= 0:
                raise ProfileError(f"{source}: {section}.{key} must be above 0")
        elif not isinstance(value, want):
            raise ProfileError(f"{source}: {section}.{key} is a {want.__name__}")
        out[key] = value
    return out


def write_profile(profile: Profile) -> str:
    """A profile file that fixes what was matched (`astiop robot profile --write`): every role's
    name, a missing one as "" (the robot has none), the units and limits in force."""
    lines = [
        '# astiop robot profile: edit a name to fix what matching got wrong; "" = the robot',
        "# has none. Read with --profile FILE (or robot.profile in the settings).",
        "[robot]",
        f'make = "{profile.make}"',
    ]
    if profile.namespace:
        lines.append(f'namespace = "{profile.namespace}"')
    lines += ["", "[roles]"]
    for role, m in profile.matches.items():
        local = m.name[len(profile.namespace) :] if profile.namespace else m.name
        note = f"  # {m.why}" if m.name else "  # none on the graph"
        lines.append(f'{role} = "{local}"{note}')
    lines += [
        "",
        "[units]",
        f'battery_percentage = "{profile.units.battery_percentage or "fraction"}"',
    ]
    limits = profile.as_dict()["limits"]
    if limits:
        lines += ["", "[limits]"] + [f"{k} = {v:g}" for k, v in limits.items()]
    lines += ["", "[map]", f'name = "{profile.map_name}"  # its named locations belong to it']
    if profile.map.geofence:
        lines.append("geofence = [{}]".format(", ".join(f"{v:g}" for v in profile.map.geofence)))
    else:
        lines.append("# geofence = [x_min, y_min, x_max, y_max]  # else the robot's /map extent")
    return "\n".join(lines) + "\n"

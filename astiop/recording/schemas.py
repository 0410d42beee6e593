"""The schemas a recording's channels carry: `ros2msg` for the robot's topics, JSON schemas for
astiop's own (turns, events, missions)."""

from __future__ import annotations

from astiop.recording import alerts, missions
from astiop.ros2.definitions import definitions
from astiop.ros2.interfaces import normalize_type, used_types

SEPARATOR = "=" * 80


def ros2msg(type_name: str, distro: str | None = None) -> str:
    """The type's definition followed by every type it uses, as rosbag2 writes `ros2msg`
    schemas: each dependency after a line of '=' and 'MSG: pkg/msg/Name'."""
    from astiop.ros2.grammar import current_distro

    defs = definitions(distro or current_distro())
    text = [defs[normalize_type(type_name)].strip()]
    for dep in used_types(type_name, distro):
        text.append(f"{SEPARATOR}\nMSG: {dep}\n{defs[dep].strip()}")
    return "\n".join(text) + "\n"


JSON_SCHEMAS = {
    "/astiop/interactions": {
        "type": "object",
        "title": "astiop interaction",
        "properties": {
            "id": {"type": "integer"},
            "prompt": {"type": "string"},
            "model": {"type": "string"},
            "answer": {"type": ["string", "null"]},
            "grounding": {"type": ["string", "null"]},
            "commands": {"type": "array"},
            "total_s": {"type": ["number", "null"]},
            "status": {"type": "string"},
        },
    },
    "/astiop/events": {
        "type": "object",
        "title": "astiop robot event",
        "properties": {
            "kind": {"type": "string"},
            "severity": {"type": "string"},
            "message": {"type": "string"},
        },
    },
    missions.TOPIC: missions.SCHEMA,
    alerts.TOPIC: alerts.SCHEMA,
}

"""What `ros2` prints back: service responses, a call still waiting for its server, failures it
reports with status 0, and the display options that shape only its text."""

from __future__ import annotations

import re
from typing import Any

_FIELD = re.compile(r"(\w+)=('(?:[^'\\]|\\.)*'|\"(?:[^\"\\]|\\.)*\"|[^,()]+)")
# What ros2 prints on stdout, with exit status 0, when nothing was done.
FAILED_WITH_STATUS_0 = re.compile(
    r"^(Setting parameter failed.*|Parameter not set.*|Node not found.*|"
    r"Failed to populate (message )?fields?.*|Goal was rejected.*)$",
    re.MULTILINE,
)


def waited_for_service(out: str) -> bool:
    """`ros2 service call` found no server of its type (ros2service/verb/call.py waits)."""
    return "waiting for service" in out and "response:" not in out


def unsent(out: str) -> bool:
    """A `ros2 service call` still waiting for its server: it sent no request yet."""
    return "requester:" not in out


def parse_response(text: str) -> dict[str, Any]:
    """Fields of the `response:` line of `ros2 service call`, flat and best effort."""
    _, _, tail = text.partition("response:")
    values: dict[str, Any] = {}
    for key, raw in _FIELD.findall(tail):
        raw = raw.strip()
        if raw in ("True", "False"):
            values[key] = raw == "True"
        elif raw[:1] in ("'", '"'):
            values[key] = raw[1:-1]
        else:
            try:
                values[key] = float(raw) if "." in raw else int(raw)
            except ValueError:
                values[key] = raw
    return values


_DISPLAY_FLAGS = {"--no-arr", "--no-str", "-f", "--full-length"}
_DISPLAY_VALUED = ("-l", "--truncate-length")


def without_display_options(argv: list[str]) -> list[str]:
    out, skip = [], False
    for token in argv:
        if skip:
            skip = False
        elif token in _DISPLAY_VALUED:
            skip = True
        elif token in _DISPLAY_FLAGS or token.startswith(("--truncate-length=", "-l")):
            continue
        else:
            out.append(token)
    return out

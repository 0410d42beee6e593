"""An MCP call's refusal: a `Refused` with its one-line reason, raised by every tool class
(tools.py, mission_tools.py, fleet_tools.py) and answered as an error by server.py."""

from __future__ import annotations

__all__ = ["Refused"]


class Refused(Exception):
    """The call was refused or failed; the reason says what, if anything, was sent."""

"""Following a mission this process drives to its end, for `astiop chat` (cli/chat.py) and
`astiop mission resume` (cli/mission.py)."""

from __future__ import annotations


def follow_mission(runner, mission_id: int) -> str:
    """Wait for the mission to end (each step is printed as it ends); Ctrl-C cancels it."""
    try:
        while not runner.wait(0.5):
            pass
    except KeyboardInterrupt:
        runner.cancel()
        runner.wait(30)
    row = runner.store.mission(mission_id) or {}
    return f"mission {mission_id} {row.get('status', '?')}: {row.get('reason') or ''}".rstrip(": ")

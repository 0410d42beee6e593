"""The mission panel: each step of the robot's latest mission as it ended (✓ done, ▶ running,
· waiting, ✗ failed), read from the store; hidden until there is a mission. A mission repeated
until stopped shows its round; a paused one what it goes on with."""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual.widgets import Static

from astiop.missions import view

STYLES = {"✓": "green", "▶": "bold cyan", "·": "dim", "–": "dim", "‖": "yellow"}
HEAD = {
    "running": "cyan",
    "paused": "yellow",
    "replaced": "yellow",
    "succeeded": "green",
    "interrupted": "yellow",
    "canceled": "yellow",
    "dropped": "dim",
}


def mission_text(m: dict[str, Any]) -> Text:
    """The panel's text; every stored string is data, never markup."""
    text = Text("mission  ", style="bold")
    text.append(view.summary(m), style=HEAD.get(m["status"], "bold red"))
    for step in m["steps"]:
        mark = view.mark(step["status"])
        text.append(f"\n{mark} ", style=STYLES.get(mark, "bold red"))
        text.append(f"{step['n']}. {view.escape_controls(step['label'])}")
        if step["detail"]:
            text.append(f"  {view.escape_controls(step['detail'])}", style="dim")
    if m["status"] == "running" and not m["pause_requested"]:
        text.append("\np pauses at the end of this step · escape cancels", style="dim")
    elif m["status"] in ("running", "paused"):
        text.append("\np resumes · escape cancels", style="dim")
    elif m["status"] == "interrupted":
        text.append(
            f"\nastiop mission resume {m['id']} | astiop mission cancel {m['id']}", style="dim"
        )
    return text


class MissionPanel(Static):
    def on_mount(self) -> None:
        self.display = False
        self.shown: dict[str, Any] | None = None

    @property
    def live(self) -> bool:
        """A mission the keys act on: running or paused."""
        return self.shown is not None and self.shown["status"] in ("running", "paused")

    def show(self, m: dict[str, Any] | None) -> None:
        if m == self.shown:
            return
        self.shown = m
        self.display = m is not None
        if m is not None:
            self.update(mission_text(m))

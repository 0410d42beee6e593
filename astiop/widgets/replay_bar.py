"""A replay's time bar: playing or paused, where it is, how long, how fast, and the keys."""

from __future__ import annotations

from rich.text import Text
from textual.widgets import Static


def clock(seconds: float) -> str:
    minutes, s = divmod(max(seconds, 0.0), 60.0)
    return f"{int(minutes):02d}:{s:04.1f}"


def bar_text(position_s: float, duration_s: float, playing: bool, speed: float, width: int) -> Text:
    head = f" {'▶' if playing else '⏸'} {speed:g}×  {clock(position_s)} / {clock(duration_s)} "
    keys = "  space ⏯  ←/→ ±1 s  [ ] speed "
    cells = max(width - len(head) - len(keys), 10)
    done = round(cells * (position_s / duration_s if duration_s > 0 else 1.0))
    return Text.assemble(
        (head, "bold"), ("━" * done, "cyan"), ("─" * (cells - done), "dim"), (keys, "dim")
    )


class ReplayBar(Static):
    DEFAULT_CSS = "ReplayBar { dock: bottom; height: 1; margin-bottom: 1; background: $boost; }"

    def __init__(self, playback):
        super().__init__(id="replay-bar")
        self.playback = playback

    def on_mount(self) -> None:
        self.tick()
        self.set_interval(0.2, self.tick)

    def tick(self) -> None:
        p = self.playback
        self.update(bar_text(p.position_s, p.duration_s, p.playing, p.speed, self.size.width or 80))

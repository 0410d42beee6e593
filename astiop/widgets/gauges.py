"""Small text gauges: the battery, and the four wheel speeds."""

from __future__ import annotations

from rich.text import Text
from textual.widgets import Static

from astiop.transports.state import MAX_WHEEL_SPEED


def bar(fraction: float, width: int, color: str) -> Text:
    fraction = min(max(fraction, 0.0), 1.0)
    filled = int(round(fraction * width))
    return Text("█" * filled, style=color) + Text("░" * (width - filled), style="grey37")


class BatteryGauge(Static):
    def show_absent(self) -> None:
        if getattr(self, "_shown", None) != "absent":
            self._shown = "absent"
            self.update(Text("battery  — the robot publishes no /battery_status", style="dim"))

    def show(self, soc: float, voltage: float, current: float, charging: bool) -> None:
        color = "green" if soc > 0.4 else "yellow" if soc > 0.2 else "red"
        text = (
            Text("battery ")
            + bar(soc, 20, color)
            + Text(
                f" {soc * 100:5.1f} %  {voltage:5.2f} V  {current:+5.2f} A"
                + ("  charging" if charging else "")
            )
        )
        shown = getattr(self, "_shown", None)
        if text.plain != shown:
            # a layout pass redraws the whole screen: only when the line's length, so its
            # wrapping, may change (the figures keep their widths)
            self.update(text, layout=shown is None or len(text.plain) != len(shown))
            self._shown = text.plain


class WheelBars(Static):
    """Signed bars around a centre line, scaled to the motor limit."""

    NAMES = ("FL", "FR", "RL", "RR")

    def show(self, wheels) -> None:
        limit = MAX_WHEEL_SPEED
        half = 12
        lines = Text()
        for name, w in zip(self.NAMES, wheels):
            n = int(round(min(abs(w) / limit, 1.0) * half))
            left = " " * (half - n) + ("█" * n if w < 0 else "")
            right = ("█" * n if w > 0 else "") + " " * (half - (n if w > 0 else 0))
            lines += (
                Text(f"{name} ")
                + Text(left.rjust(half), style="red")
                + Text("│")
                + Text(right.ljust(half), style="green")
                + Text(f" {w:+6.2f} rad/s\n")
            )
        self.update(lines)

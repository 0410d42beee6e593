"""Text panels that change often (the robot's clock, its speed) without a layout pass each time."""

from __future__ import annotations

from rich.cells import cell_len
from rich.text import Text
from textual.widgets import Static


def show_text(panel: Static, text: Text, shown: str | None) -> str:
    """Show `text` in `panel` unless it shows it already (`shown`, the plain text last shown);
    returns what it shows. A layout pass, which redraws the whole screen, only when the panel's
    height may change: another line count, or a line that wraps."""
    if text.plain == shown:
        return shown
    width = panel.content_size.width
    lines = text.plain.split("\n")
    same_height = (
        shown is not None
        and len(lines) == shown.count("\n") + 1
        and all(cell_len(line) <= width for line in [*lines, *shown.split("\n")])
    )
    panel.update(text, layout=not same_height)
    return text.plain

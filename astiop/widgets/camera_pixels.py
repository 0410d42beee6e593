"""The camera as real pixels where the terminal draws images: Sixel (xterm -ti vt340, foot,
WezTerm, Windows Terminal, iTerm2) or kitty's graphics protocol, through textual-image's widgets.
Which one is asked of the terminal once, before the console starts (textual-image asks with
escape sequences, which it cannot once Textual reads the keys); everywhere else (tmux 3.3,
GNOME Terminal, the browser tab) the camera is drawn in half-block cells (`camera_view`)."""

from __future__ import annotations

import logging
import sys

from textual.widget import Widget

log = logging.getLogger("astiop.console")
KINDS = ("sixel", "tgp")


def detect(setting: str = "auto") -> str | None:
    """'sixel' or 'tgp' where this terminal draws images, else None (half-block cells, and
    with `setting` "cells": `console.camera`). Asks the terminal: call it before the console
    runs, on its own terminal (a tty)."""
    if setting == "cells":
        return None
    out, into = sys.__stdout__, sys.__stdin__
    if out is None or into is None or not out.isatty() or not into.isatty():
        return None
    try:
        from textual_image import renderable  # asks the terminal as it is imported
    except Exception as exc:  # noqa: BLE001 - cells then, and why in the log
        log.info("the terminal's image support not known: %s", exc)
        return None
    kinds = {renderable.SixelImage: "sixel", renderable.TGPImage: "tgp"}
    kind = kinds.get(renderable.Image)
    if kind is not None:
        import textual_image.widget  # noqa: F401 - it asks the cell's size in pixels now too
    return kind


def pixel_widget(kind: str) -> Widget:
    """textual-image's widget for `kind` (one of KINDS), its image set frame by frame."""
    from textual_image.widget import SixelImage, TGPImage

    widget = SixelImage() if kind == "sixel" else TGPImage()
    widget.id = "camera-pixels"
    return widget

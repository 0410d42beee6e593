"""The Dashboard's map as an instrument: a click (or enter on the keyboard's cursor) on the floor
posts `PointPicked`, a drag from the point the way the robot should face gives it a heading,
a click on another robot of the fleet names it; the wheel, `+`/`-`, shift+arrows
and `0` zoom, pan and fit; `z` draws a zone corner by corner (`ZoneDrawn`). The drawing is
`MapCanvas`'s; where a cell is in metres, `map_viewport`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from textual import events
from textual.binding import Binding
from textual.message import Message

from astiop.widgets.map_canvas import FleetRobot, MapCanvas, Place
from astiop.widgets.map_legend import KEEPOUT, SLOW, legend_items
from astiop.widgets.map_viewport import ZOOM_STEP, pick

__all__ = ["KEEPOUT", "SLOW", "FleetRobot", "Place", "WarehouseMapView", "legend_items"]


class WarehouseMapView(MapCanvas):
    DEFAULT_CSS = "WarehouseMapView { height: 1fr; width: 1fr; min-height: 10; }"
    can_focus = True
    BINDINGS = [
        Binding("enter", "choose", "Point menu"),
        Binding("z", "draw", "Draw zone"),
        Binding("plus,equals_sign", "zoom(1)", "Zoom in", show=False),  # said under the map
        Binding("minus", "zoom(-1)", "Zoom out", show=False),
        Binding("0", "fit", "Fit"),
        *(Binding(k, f"cursor({dx}, {dy})", show=False) for k, dx, dy in
          (("up", 0, -1), ("down", 0, 1), ("left", -1, 0), ("right", 1, 0))),
        *(Binding(f"shift+{k}", f"pan({dx}, {dy})", show=False) for k, dx, dy in
          (("up", 0, -1), ("down", 0, 1), ("left", -1, 0), ("right", 1, 0))),
        Binding("space", "corner", "Add corner"),
        Binding("backspace", "undo_corner", "Undo corner"),
        Binding("escape", "cancel_draw", "Cancel zone"),
    ]  # fmt: skip

    @dataclass
    class PointPicked(Message):
        """A point chosen on the floor (metres), or another robot of the fleet (`robot`);
        `theta`: the heading dragged from it (radians, the map's frame), None if only clicked."""

        x: float
        y: float
        robot: str | None
        theta: float | None = None

    @dataclass
    class ZoneDrawn(Message):
        corners: list[tuple[float, float]]

    def __init__(self, geometry, **kwargs):
        super().__init__(geometry, **kwargs)
        self.steers = True  # False: no cursor on the arrows (a replay's clock has them)
        self._pressed: tuple[int, int] | None = None  # the map cell a mouse button went down on
        self._drag_done = False  # a drag was picked on the button's release: its click is not

    # -- pointing, zooming, drawing -------------------------------------------------------
    def on_mouse_down(self, event: events.MouseDown) -> None:
        at = event.get_content_offset(self)
        on_map = at is not None and at.y < self._map_rows()
        self._pressed = (at.x, at.y) if at is not None and on_map else None

    def on_mouse_up(self, event: events.MouseUp) -> None:
        """Let go away from where it was pressed: the point pressed, facing the way dragged (the
        click that follows is not a second pick)."""
        at = event.get_content_offset(self)
        pressed, self._pressed = self._pressed, None
        self._drag_done = False
        if pressed is None or at is None or self.draft is not None:
            return
        if _dragged(pressed, (at.x, at.y)):
            self._drag_done = True
            self.cursor = pressed
            self._say_where()
            self._choose_heading(pressed, (at.x, at.y))

    def on_click(self, event: events.Click) -> None:
        at = event.get_content_offset(self)
        if self._drag_done:
            self._drag_done = False
            return
        if at is None or at.y >= self._map_rows():
            return  # the border or the legend
        self.cursor = (at.x, at.y)
        self._say_where()
        self._choose_cell(at.x, at.y, corner=self.draft is not None)

    def _choose_heading(self, start: tuple[int, int], end: tuple[int, int]) -> None:
        """The point pressed, facing where the button was let go."""
        frame = self.frame
        x0, y0 = frame.cell_centre(*start)
        x1, y1 = frame.cell_centre(*end)
        p = pick(frame, *start, [])  # a drag always means the floor, never a robot there
        self.post_message(self.PointPicked(p.x, p.y, None, math.atan2(y1 - y0, x1 - x0)))

    def on_mouse_scroll_up(self, event: events.MouseScrollUp) -> None:
        self._zoom_at(ZOOM_STEP, event)

    def on_mouse_scroll_down(self, event: events.MouseScrollDown) -> None:
        self._zoom_at(1 / ZOOM_STEP, event)

    def _zoom_at(self, factor: float, event: events.MouseEvent) -> None:
        event.stop()
        at = event.get_content_offset(self)
        self._zoom(factor, at if at is not None and at.y < self._map_rows() else None)

    def _zoom(self, factor: float, cell=None) -> None:
        frame = self.frame
        about = frame.cell_centre(*cell) if cell is not None else None
        self.viewport.zoom_by(factor, self.size.width, 2 * self._map_rows(), self.bounds, about)
        self._redraw()
        self._say_where()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        drawing = self.draft is not None
        if action in ("corner", "undo_corner", "cancel_draw"):
            return drawing  # else the key goes on (space, escape: the screen's and app's)
        if action in ("cursor", "pan"):
            return self.steers  # else the arrows step a replay's clock
        if action == "draw":
            return self.steers and not drawing
        return True

    def _choose_cell(self, col: int, row: int, corner: bool) -> None:
        robots = [(r.name, r.x, r.y) for r in self.others]
        p = pick(self.frame, col, row, [] if corner else robots)
        if corner and self.draft is not None:
            self.draft.append((round(p.x, 2), round(p.y, 2)))
            self._changed_draft()
        else:
            self.post_message(self.PointPicked(p.x, p.y, p.robot))

    def action_choose(self) -> None:
        if self.draft is not None:  # enter closes the zone being drawn
            corners, self.draft = self.draft, None
            self._changed_draft()
            self.post_message(self.ZoneDrawn(corners))
            return
        self._choose_cell(*self._cursor(), corner=False)

    def action_corner(self) -> None:
        self._choose_cell(*self._cursor(), corner=True)

    def action_undo_corner(self) -> None:
        if self.draft:
            self.draft.pop()
            self._changed_draft()

    def action_cancel_draw(self) -> None:
        self.draft = None
        self._changed_draft()

    def action_draw(self) -> None:
        self.draft = []
        self._changed_draft()

    def _changed_draft(self) -> None:
        self._legend_width = -1
        self._pixels = None
        self.refresh()
        self._say_where()

    def action_zoom(self, direction: int) -> None:
        self._zoom(ZOOM_STEP if direction > 0 else 1 / ZOOM_STEP, self._cursor())

    def action_fit(self) -> None:
        self.viewport.fit()
        self._redraw()
        self._say_where()

    def action_pan(self, dx: int, dy: int) -> None:
        w, h = self.size.width, self._map_rows()
        self.viewport.pan_cells(dx * max(w // 4, 1), dy * max(h // 4, 1), self.frame)
        self._redraw()
        self._say_where()

    def action_cursor(self, dx: int, dy: int) -> None:
        """One cell; off the view's edge the view pans a quarter instead."""
        col, row = self._cursor()
        w, h = self.size.width, self._map_rows()
        col, row = col + dx, row + dy
        if not (0 <= col < w and 0 <= row < h):
            self.action_pan(dx, dy)
            col, row = min(max(col, 0), w - 1), min(max(row, 0), h - 1)
        self.cursor = (col, row)
        self.refresh()
        self._say_where()

    def _cursor(self) -> tuple[int, int]:
        w, h = self.size.width, self._map_rows()
        if w <= 0 or h <= 0:
            return (0, 0)  # not laid out yet: placed once it is
        if self.cursor is None:  # first at the robot, else the middle
            st = self.robot_state
            col, row = w // 2, h // 2
            if st is not None and st.pose is not None and math.isfinite(st.pose.x):
                col, row = self.frame.cell_of(st.pose.x, st.pose.y)
            self.cursor = (min(max(col, 0), w - 1), min(max(row, 0), h - 1))
        return self.cursor

    def on_focus(self) -> None:
        self._say_where()
        self.refresh()

    def on_blur(self) -> None:
        self.refresh()

    def on_resize(self) -> None:
        self._say_where()

    def _say_where(self) -> None:
        """Under the map's border: where the cursor points, the zoom, the zone being drawn."""
        if self.size.width <= 0 or self._map_rows() <= 0:
            return
        if not self.has_focus and self.draft is None:
            self.border_subtitle = f"zoom {self.viewport.zoom:g}×"
            return
        x, y = self.frame.cell_centre(*self._cursor())
        said = f"({x:.2f}, {y:.2f}) m  zoom {self.viewport.zoom:g}× (+/-, wheel)"
        if self.draft is not None:  # the keys that end it; space and clicks add corners
            said = f"zone: {len(self.draft)} corners, enter ends, esc cancels  {said}"
        self.border_subtitle = said

    # -- the legend -----------------------------------------------------------------------


def _dragged(a: tuple[int, int], b: tuple[int, int]) -> bool:
    """Let go two cells or more from where it was pressed (a cell is half as wide as high)."""
    return abs(b[0] - a[0]) >= 2 or abs(b[1] - a[1]) >= 1

"""What the Dashboard's map asks for, done: a clicked point sends the current robot there (the
command the rules plan for a typed "go to x, y", run by the app's goal path: the gateway's
review, safety, lease and the operator's confirmation, as every goal) or is saved as a place; a
clicked robot of the fleet becomes the current one; a drawn polygon is stored as a zone."""

from __future__ import annotations

import math
from collections.abc import Callable

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import Label, OptionList
from textual.widgets.option_list import Option

from astiop.screens import control
from astiop.screens.base import services_of
from astiop.screens.modals import FormModal
from astiop.store import LocationError, StoreError
from astiop.transports.state import OccupancyGrid
from astiop.warehouse import WarehouseMap
from astiop.widgets.map_view import FleetRobot, WarehouseMapView
from astiop.zones import KINDS, ZoneError


def occupied(geometry, x: float, y: float) -> str:
    """What fixed obstacle of the map the point is on ("" on the floor): a wall, a rack, a
    pillar of the known layout, or an occupied cell of the robot's /map."""
    if isinstance(geometry, WarehouseMap):
        for kind, (x0, y0, x1, y1) in geometry.static_rects:
            if kind in ("wall", "shelf", "pillar") and x0 <= x <= x1 and y0 <= y <= y1:
                return "a rack" if kind == "shelf" else f"a {kind}"
    elif isinstance(geometry, OccupancyGrid):
        col = math.floor((x - geometry.origin_x) / geometry.resolution)
        row = math.floor((y - geometry.origin_y) / geometry.resolution)
        inside = 0 <= row < geometry.height and 0 <= col < geometry.width
        if inside and geometry.cells[row, col] >= 50:
            return "an occupied cell of the robot's map"
    return ""


class PointMenuModal(ModalScreen[str | None]):
    """What to do with a point of the floor: "send" or "save" (None: nothing)."""

    BINDINGS = [Binding("escape", "dismiss(None)", "Cancel")]

    def __init__(self, robot: str, x: float, y: float, theta: float | None = None):
        super().__init__()
        self.robot, self.x, self.y, self.theta = robot, x, y, theta

    def compose(self) -> ComposeResult:
        facing = "" if self.theta is None else f", facing {math.degrees(self.theta):.0f}°"
        with Vertical(id="modal-box"):
            yield Label(f"The point ({self.x:.2f}, {self.y:.2f}) m{facing}", classes="panel-title")
            yield OptionList(
                Option(f"Send {self.robot} here ({self.x:.2f}, {self.y:.2f}){facing}", id="send"),
                Option("Save this point as…", id="save"),
                id="point-menu",
            )

    def on_mount(self) -> None:
        menu = self.query_one(OptionList)
        menu.highlighted = 0  # enter sends, as the first line says
        menu.focus()

    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        self.dismiss(event.option.id)


class MapActions:
    """The Dashboard's map's requests, for `app` (the console); `reload()` draws the places and
    zones again once one was stored."""

    def __init__(self, app, reload: Callable[[], None]):
        self.app = app
        self.reload = reload

    def others(self) -> list[FleetRobot]:
        """The fleet's robots but the current one, where they said they are (none alone)."""
        app = self.app
        if app.fleet is None:
            return []
        current = app.current_robot
        return [
            FleetRobot(r.name, r.x, r.y, r.theta or 0.0, r.plan)
            for r in app.fleet_rows()
            if r.name != current and r.x is not None and r.y is not None
        ]

    def point_picked(self, msg: WarehouseMapView.PointPicked) -> None:
        app = self.app
        if msg.robot is not None:
            if msg.robot == app.current_robot:
                return
            control.use_robot(app, msg.robot)
            return
        x, y = round(msg.x, 2), round(msg.y, 2)  # a centimetre: what the menu says is sent
        on = occupied(services_of(app).gateway.map_geometry(), x, y)
        if on:  # said before anything is asked: no robot stands there, no place is there
            app.notify(f"({x:.2f}, {y:.2f}) is on {on}: pick a point of the floor",
                       severity="error", markup=False)  # fmt: skip
            return

        theta = None if msg.theta is None else round(msg.theta, 4)

        def chosen(what: str | None) -> None:
            if what == "send":
                app.goto_point(x, y, theta)
            elif what == "save":
                self.save_point(x, y, theta or 0.0)

        app.push_screen(PointMenuModal(app.current_robot, x, y, theta), chosen)

    def save_point(self, x: float, y: float, theta: float = 0.0) -> None:
        """Asked a name, stored as `astiop locations add NAME X Y THETA` stores it."""
        app = self.app
        fields = [
            ("name", "name (letters, digits, _ or -)", ""),
            ("description", "description", ""),
        ]

        def done(values: dict | None) -> None:
            if values is None:
                return
            store = services_of(app).store
            try:
                loc = store.add_location(values["name"].strip(), x, y, theta, values["description"])
            except (LocationError, StoreError) as exc:
                app.notify(str(exc), severity="error", markup=False)
                return
            app.notify(f"saved {loc.name} at ({loc.x:.2f}, {loc.y:.2f})", markup=False)
            self.reload()

        app.push_screen(FormModal(f"Save the point ({x:.2f}, {y:.2f}) as", fields), done)

    def zone_drawn(self, msg: WarehouseMapView.ZoneDrawn) -> None:
        """Its kind, limit and name asked, then stored as `astiop zones add` stores it."""
        app = self.app
        corners = msg.corners
        if len(corners) < 3:  # said before asking anything more
            app.notify(f"a zone needs at least 3 corners, {len(corners)} given", severity="error")
            return
        fields = [
            ("name", "zone name (letters, digits, _ or -)", ""),
            ("kind", "keepout (no goal inside, no plan through) or speed", "keepout"),
            ("speed", "speed limit inside, m/s (a speed zone)", ""),
        ]

        def done(values: dict | None) -> None:
            if values is None:
                return
            kind = values["kind"].strip().lower()
            speed = None
            if kind == "speed":
                try:
                    speed = float(values["speed"])
                except ValueError:
                    app.notify(f"bad speed '{values['speed'][:20]}': a number in m/s",
                               severity="error", markup=False)  # fmt: skip
                    return
            store = services_of(app).store
            try:
                zone = store.add_zone(values["name"].strip(), kind, corners, speed)
            except (ZoneError, StoreError) as exc:
                app.notify(str(exc), severity="error", markup=False)
                return
            app.notify(f"added the {zone.words} ({len(zone.corners)} corners)", markup=False)
            self.reload()

        title = f"A zone of {len(corners)} corners: {' or '.join(KINDS)}"
        app.push_screen(FormModal(title, fields), done)

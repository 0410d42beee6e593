"""Locations: named waypoints; add, rename, delete and send the robot there."""

from __future__ import annotations

import math

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.widgets import DataTable, Footer, Header

from astiop.bounded import escape_controls
from astiop.screens.base import ConsoleScreen
from astiop.screens.modals import ConfirmModal, FormModal
from astiop.store import Location, LocationError


class LocationsScreen(ConsoleScreen):
    BINDINGS = [
        Binding("a", "add", "Add"),
        Binding("r", "rename", "Rename"),
        Binding("delete,d", "delete", "Delete"),
        Binding("g", "goto", "Go to"),
    ]

    def __init__(self):
        super().__init__()
        self.locations: list[Location] = []

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        yield DataTable(id="locations-table", cursor_type="row", zebra_stripes=True)
        yield Footer()

    def on_mount(self) -> None:
        self.query_one(DataTable).add_columns("name", "x (m)", "y (m)", "θ (°)", "description")
        self.reload()

    def reload(self) -> None:
        store = self.services.store
        self.locations = store.list_locations()
        self.sub_title = f"map {store.map_name}: {len(self.locations)} places"
        table = self.query_one(DataTable)
        table.clear()
        for loc in self.locations:
            table.add_row(
                Text(loc.name),
                f"{loc.x:.2f}",
                f"{loc.y:.2f}",
                f"{math.degrees(loc.theta):.1f}",
                Text(escape_controls(loc.description)),  # data: never markup, never raw
            )

    def selected(self) -> Location | None:
        table = self.query_one(DataTable)
        if not self.locations:
            return None
        return self.locations[min(table.cursor_row, len(self.locations) - 1)]

    def action_add(self) -> None:
        pose = self.app.robot_state.pose
        x, y, th = (pose.x, pose.y, math.degrees(pose.theta)) if pose else (0.0, 0.0, 0.0)
        fields = [
            ("name", "name (letters, digits, _ or -)", ""),
            ("x", "x (m) — the robot's pose by default", f"{x:.2f}"),
            ("y", "y (m)", f"{y:.2f}"),
            ("theta", "θ (degrees)", f"{th:.1f}"),
            ("description", "description", ""),
        ]

        def done(values: dict | None) -> None:
            if values is None:
                return
            try:
                x, y, th = (float(values[k]) for k in ("x", "y", "theta"))
            except ValueError:
                self.notify("x, y and θ must be numbers", severity="error")
                return
            try:
                loc = self.services.store.add_location(
                    values["name"].strip(), x, y, math.radians(th), values["description"]
                )
            except LocationError as exc:
                self.notify(str(exc), severity="error", markup=False)
                return
            self.notify(f"added {loc.name}", markup=False)
            self.reload()

        self.app.push_screen(FormModal("Add a named location", fields), done)

    def action_rename(self) -> None:
        loc = self.selected()
        if loc is None:
            return

        def done(values: dict | None) -> None:
            if values is None:
                return
            try:
                new = self.services.store.rename_location(loc.name, values["name"].strip())
            except LocationError as exc:
                self.notify(str(exc), severity="error", markup=False)
                return
            self.notify(f"renamed {loc.name} to {new.name}", markup=False)
            self.reload()

        self.app.push_screen(
            FormModal(f"Rename {loc.name}", [("name", "new name", loc.name)]), done
        )

    def action_delete(self) -> None:
        loc = self.selected()
        if loc is None:
            return

        def done(ok: bool | None) -> None:
            if ok:
                self.services.store.remove_location(loc.name)
                self.notify(f"removed {loc.name}", markup=False)
                self.reload()

        self.app.push_screen(ConfirmModal(f"Delete the location {loc.name}?"), done)

    def action_goto(self) -> None:
        loc = self.selected()
        if loc is not None:
            self.app.goto_location(loc.name)

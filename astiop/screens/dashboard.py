"""Dashboard (Fig. 16a): the robot, the graph's topics, the agent, the map, the latest events."""

from __future__ import annotations

import math

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.containers import Vertical, VerticalScroll
from textual.screen import Screen
from textual.widgets import DataTable, Footer, Header, Static

from astiop.agent.llm import LLMError
from astiop.sim.state import SimState
from astiop.widgets.gauges import BatteryGauge
from astiop.widgets.warehouse_map import WarehouseMapView

STATE_COLOURS = {
    "idle": "green",
    "navigating": "cyan",
    "docking": "cyan",
    "charging": "blue",
    "blocked": "yellow",
    "e_stopped": "bold red",
    "fault": "bold red",
}


class DashboardScreen(Screen):
    def compose(self) -> ComposeResult:
        services = self.app.services
        warehouse = services.store.warehouse
        yield Header(show_clock=False)
        with Vertical(id="dash-grid"):
            with Vertical(id="dash-left"):
                yield WarehouseMapView(warehouse, id="map-panel")
                events = DataTable(id="events", cursor_type="none", zebra_stripes=True)
                yield events
            with VerticalScroll(id="dash-right"):
                yield Static(id="robot", classes="panel")
                yield BatteryGauge(id="battery", classes="panel")
                yield Static(id="agent", classes="panel")
                yield DataTable(id="topics", cursor_type="none")
                yield Static(id="services", classes="panel")
        yield Footer()

    def on_screen_resume(self) -> None:
        # on first show too; locations may have changed on the Locations screen
        self.query_one(WarehouseMapView).set_locations(
            [(loc.x, loc.y) for loc in self.app.services.store.list_locations()]
        )

    def on_mount(self) -> None:
        topics = self.query_one("#topics", DataTable)
        topics.add_columns("topic", "type", "Hz", "age")
        events = self.query_one("#events", DataTable)
        events.add_columns("sim t", "kind", "message")
        cat = self.app.services.graph.catalog
        lines = [f"{s.name}  [dim]{s.type}[/]" for s in cat.services.values()]
        lines += [f"{a.name}  [dim]{a.type}[/] (action)" for a in cat.actions.values()]
        self.query_one("#services", Static).update("[b]services & actions[/]\n" + "\n".join(lines))
        self.show_agent()
        self.check_endpoint()
        self.set_interval(1.0, self.show_topics)
        self.show_topics()
        if self.app.state is not None:
            self.show_state(self.app.state)

    def show_agent(self) -> None:
        ep = self.app.services.endpoint
        turn = self.app.last_turn
        if ep.is_rules:
            reach = "rule-based baseline (no LLM)"
        elif ep.local:
            reach = "ready" if ep.server else "starts on first request"
        else:
            reach = getattr(self, "_reach", f"checking {ep.spec.url}…")
        latency = (
            f"last turn {turn.total_s:.1f} s, first token {turn.ttft_s or 0:.1f} s"
            if turn
            else "no turn yet"
        )
        self.query_one("#agent", Static).update(
            f"[b]agent[/]   model {ep.spec.raw}  ({reach})\n{latency}"
        )

    @work(exclusive=True, group="reach")
    async def check_endpoint(self) -> None:
        ep = self.app.services.endpoint
        if ep.is_rules or ep.local:
            return
        try:
            served = await ep.client().list_models()
            self._reach = f"answers at {ep.spec.url}, serving {len(served)} model(s)"
        except LLMError as exc:
            self._reach = f"DOWN: {exc}"
        self.show_agent()

    def show_topics(self) -> None:
        backend = self.app.services.graph.backend
        stats = getattr(backend, "topic_stats", None)
        table = self.query_one("#topics", DataTable)
        table.clear()
        if stats is None:
            for name, spec in self.app.services.graph.catalog.topics.items():
                table.add_row(name, spec.type.split("/")[-1], "-", "-")
            return
        for s in stats():
            age = "never" if math.isinf(s.age_s) else f"{s.age_s:.1f}s"
            table.add_row(s.name, s.type.split("/")[-1], f"{s.measured_hz:.1f}", age)

    def show_state(self, st: SimState) -> None:
        self.query_one(WarehouseMapView).show(st)
        colour = STATE_COLOURS.get(st.state, "white")
        text = Text.assemble(
            ("robot  ", "bold"),
            (st.state.upper(), colour),
            f"   mode {st.mode}   t {st.t:.1f} s\n",
            f"pose   x {st.x:6.2f} m  y {st.y:6.2f} m  θ {math.degrees(st.theta):6.1f}°\n",
            f"speed  {st.speed:.2f} m/s  ω {st.wz:+.2f} rad/s\n",
            f"goal   {st.active_goal or '-'}"
            + (f"  ({st.distance_remaining:.1f} m to go)" if st.active_goal else "")
            + "\n",
            ("fault  " + (st.fault or "none"), "bold red" if st.fault else ""),
            f"\nconveyor {'loaded' if st.conveyor_loaded else 'empty'}"
            f"{'  running' if st.conveyor_direction else ''}  lamp {st.lamp}"
            f"  obstacles seen {len(st.detected)}",
        )
        if text.plain != getattr(self, "_robot_text", None):
            self._robot_text = text.plain
            self.query_one("#robot", Static).update(text)
        self.query_one("#battery", BatteryGauge).show(
            st.battery_soc, st.battery_voltage, st.battery_current, st.battery_charging
        )
        self._show_events(st.event_seq)

    def _show_events(self, seq: int) -> None:
        if seq == getattr(self, "_event_seq", None):
            return
        self._event_seq = seq
        sim = self.app.services.sim
        table = self.query_one("#events", DataTable)
        table.clear()
        for ev in reversed(sim.events_since(0)[-6:] if sim else []):
            table.add_row(f"{ev.t:.1f}", ev.kind, ev.message)

"""Dashboard: the robot, the graph's topics, the agent, the map, the latest events.

Everything here comes from the robot layer's `RobotState`, so it reads the same on the
simulator and on a real robot; a topic the robot lacks shows as absent.
"""

from __future__ import annotations

import math

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical, VerticalScroll
from textual.widgets import DataTable, Footer, Header, Static

from astiop.agent.models.probe import probe
from astiop.bounded import escape_controls
from astiop.robot.camera import CameraReading
from astiop.screens import mission_commands
from astiop.screens.base import ConsoleScreen
from astiop.screens.map_actions import MapActions
from astiop.screens.messages import RobotStateSampled, TurnFinished
from astiop.screens.panel_text import show_text
from astiop.transports.state import RobotState, TopicStat
from astiop.widgets.camera_view import CameraView
from astiop.widgets.gauges import BatteryGauge
from astiop.widgets.live_table import LiveTable
from astiop.widgets.map_view import Place, WarehouseMapView
from astiop.widgets.mission_panel import MissionPanel

STATE_COLOURS = {
    "idle": "green",
    "navigating": "cyan",
    "docking": "cyan",
    "charging": "blue",
    "blocked": "yellow",
    "e_stopped": "bold red",
    "fault": "bold red",
    "lost": "bold red",
}
EVENT_ROWS = 6
GAP = "   "


def _num(value: float | None, fmt: str) -> str:
    return "—" if value is None or not math.isfinite(value) else format(value, fmt)


def _rate_and_age(s: TopicStat) -> tuple[str, str]:
    if math.isnan(s.measured_hz):
        return "-", "unwatched"  # nothing here subscribes to it (on a live robot)
    return f"{s.measured_hz:.1f}", "never" if math.isinf(s.age_s) else f"{s.age_s:.1f}s"


def motion_key(st: RobotState) -> tuple:
    """All the Dashboard shows but the clock, the scan and the battery, at the precision shown:
    while it holds, the robot is still and need not be sampled as often (the app's pace)."""
    p, v, status = st.pose, st.velocity, st.status
    return (
        st.state_word,
        status and (status.mode, status.active_goal, status.fault, round(status.speed, 2)),
        p and (round(p.x, 2), round(p.y, 2), round(p.theta, 3)),
        v and tuple(round(c, 2) for c in v),
        st.lost_s is None,
        st.plan,
        st.obstacles,
        st.conveyor,
        st.battery and st.battery.charging,
    )


def robot_text(st: RobotState) -> Text:
    state = st.state_word
    status = st.status
    # each gap ends the run before it: a run that starts with spaces loses them in some SVG
    # viewers, which showed the snapshots' robot line as "CHARGINGmode auto"
    text = Text.assemble(
        ("robot  ", "bold"), (state.upper() + GAP, STATE_COLOURS.get(state, "white"))
    )
    if st.lost_s is not None:  # what follows is what it said last, not what it does now
        text.append(f"no message for {st.lost_s:.0f} s: last known{GAP}", style="bold red")
    elif status:
        text.append(f"mode {status.mode}{GAP}")
    text.append(f"t {st.t:.1f} s\n")
    if st.pose is None:
        text.append("pose   — no /robot_pose or /odom\n", style="dim")
    else:
        p = st.pose
        deg = math.degrees(p.theta) if math.isfinite(p.theta) else math.nan
        text.append(
            f"pose   x {_num(p.x, '6.2f')} m  y {_num(p.y, '6.2f')} m  θ {_num(deg, '6.1f')}°\n"
        )
    wz = f"  ω {st.velocity[2]:+.2f} rad/s" if st.velocity else ""
    text.append(f"speed  {_num(st.speed, '.2f')} m/s{wz}\n")
    goal = status.active_goal if status else ""
    remaining = st.distance_remaining
    text.append(f"goal   {goal or '-'}")
    if goal and remaining is not None:
        text.append(f"  ({remaining:.1f} m to go)")
    fault = status.fault if status else ""
    text.append("\nfault  " + (fault or "none"), style="bold red" if fault else "")
    conveyor = st.conveyor
    if conveyor is not None:
        text.append(
            f"\nconveyor {'loaded' if conveyor.loaded else 'empty'}"
            f"{'  running' if conveyor.running else ''}  lamp {conveyor.lamp}"
        )
    seen = "—" if st.obstacles is None else str(len(st.obstacles))
    text.append(f"\nobstacles seen {seen}")
    return text


class DashboardScreen(ConsoleScreen):
    BINDINGS = [
        Binding("escape", "cancel_mission", "Cancel mission", show=False),
        Binding("p", "pause_mission", "Pause/resume mission", show=False),
    ]

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        with Vertical(id="dash-grid"):
            with Vertical(id="dash-left"):
                yield WarehouseMapView(self.services.gateway.map_geometry(), id="map-panel")
                yield DataTable(id="events", cursor_type="none", zebra_stripes=True)
            with VerticalScroll(id="dash-right"):
                yield MissionPanel(id="mission", classes="panel")
                yield Static(id="robot", classes="panel")
                yield BatteryGauge(id="battery", classes="panel")
                pixels = getattr(self.app, "camera_pixels", None)  # the console's (AstiopApp)
                yield CameraView(self._camera, self._robot_clock, pixels=pixels, id="camera")
                yield Static(id="agent", classes="panel")
                yield LiveTable(id="topics", cursor_type="none")
                yield Static(id="services", classes="panel")
        yield Footer()

    def _camera(self) -> CameraReading:
        return self.services.gateway.camera()  # the current robot's: a fleet's may change

    def _robot_clock(self) -> float | None:
        """The robot's clock as last sampled: a camera frame's age is measured on it."""
        return getattr(self, "_robot_t", None)

    def on_mount(self) -> None:
        self.map_actions = MapActions(self.app, self._show_places)
        # a replay's clock has the arrows; its robot takes no goal
        self.query_one(WarehouseMapView).steers = self.services.gateway.playback is None
        self.reach = ""
        self.last_turn = None
        topics = self.query_one("#topics", DataTable)
        for label in ("topic", "type", "Hz", "age"):
            topics.add_column(label, key=label.lower())
        self.query_one("#events", DataTable).add_columns("t", "kind", "message")
        cat = self.services.gateway.catalog
        text = Text("services & actions\n", style="bold")
        for s in cat.services.values():
            text.append(s.name + "  ").append(s.type + "\n", style="dim")
        for a in cat.actions.values():
            text.append(a.name + "  ").append(a.type, style="dim").append(" (action)\n")
        self.query_one("#services", Static).update(text)
        self.show_agent()
        self.check_endpoint()
        self.show_state(self.app.robot_state)
        self.show_topics(self.app.topic_stats)
        self._show_events()
        self.set_interval(1.0, self.read_mission)
        self.read_mission()

    @work(thread=True, exclusive=True, group="mission", exit_on_error=False)
    def read_mission(self) -> None:
        """The latest mission, from the store (any process may be driving it)."""
        from astiop.missions import view

        store = self.services.store
        row = store.latest_mission()
        m = view.as_json(store, row["id"]) if row else None
        self.app.call_from_thread(self.query_one(MissionPanel).show, m)

    def action_cancel_mission(self) -> None:
        """Escape: the live mission is canceled by the process driving it (this one or
        another), which stops the robot."""
        if self.query_one(MissionPanel).live:
            mission_commands.control(self.app, "cancel")
            self.set_timer(0.3, self.read_mission)

    def action_pause_mission(self) -> None:
        """p: hold the live mission at the end of its step, or let a held one go on."""
        if self.query_one(MissionPanel).live:
            mission_commands.control(self.app, "toggle")
            self.set_timer(0.3, self.read_mission)

    def on_screen_resume(self) -> None:
        # on first show too; locations may have changed on the Locations screen, and events
        # may have come while another screen was shown
        self._show_places()
        self._show_events()

    def _show_places(self) -> None:
        view = self.query_one(WarehouseMapView)
        view.set_locations(
            [Place(loc.name, loc.x, loc.y) for loc in self.services.store.list_locations()]
        )
        view.set_zones(self.services.store.list_zones())  # added from the CLI meanwhile, too

    def on_warehouse_map_view_point_picked(self, msg: WarehouseMapView.PointPicked) -> None:
        self.map_actions.point_picked(msg)

    def on_warehouse_map_view_zone_drawn(self, msg: WarehouseMapView.ZoneDrawn) -> None:
        self.map_actions.zone_drawn(msg)

    def on_robot_state_sampled(self, msg: RobotStateSampled) -> None:
        self.show_state(msg.state)
        if msg.events:
            self._show_events()
        if msg.stats is not None:
            self.show_topics(msg.stats)

    def on_turn_finished(self, msg: TurnFinished) -> None:
        self.last_turn = msg.result
        self.show_agent()

    def show_agent(self) -> None:
        ep = self.services.endpoint
        if ep.is_rules:
            reach = "rule-based baseline (no LLM)"
        elif ep.local:
            reach = "ready" if ep.server else "starts on first request"
        else:
            reach = self.reach or f"checking {ep.spec.url}…"
        turn = self.last_turn
        if turn is None:
            latency = "no turn yet"
        else:
            latency = f"last turn {turn.total_s:.1f} s, first token {turn.ttft_s or 0:.1f} s"
            latency += f", {turn.prompt_tokens}+{turn.completion_tokens} tokens"
            if turn.error:
                latency += f"\nerror: {turn.error}"
        text = Text("agent", style="bold")
        text.append(f"   model {ep.spec.raw}  ({reach})\n{latency}")
        self.query_one("#agent", Static).update(text)

    @work(exclusive=True, group="reach", exit_on_error=False)
    async def check_endpoint(self) -> None:
        ep = self.services.endpoint
        if ep.is_rules or ep.local:
            return
        reach = await probe(ep)
        self.reach = reach.detail if reach.answers else f"DOWN: {reach.detail}"
        self.show_agent()

    def show_topics(self, stats: list[TopicStat]) -> None:
        """Rebuilt when the topics change; else only the cells whose text changed are replaced
        (rebuilding the table every second was a third of the dashboard's CPU)."""
        table = self.query_one("#topics", DataTable)
        rows = [(s.name, s.type, *_rate_and_age(s)) for s in stats]
        shown: list[tuple[str, str, str, str]] = getattr(self, "_topic_rows", [])
        if [r[:2] for r in rows] != [r[:2] for r in shown]:
            table.clear()
            for name, type_, hz, age in rows:
                table.add_row(Text(name), Text(type_.split("/")[-1]), hz, age, key=name)
        else:
            for (name, _t, hz, age), (_n, _t2, old_hz, old_age) in zip(rows, shown):
                for column, new, old in (("hz", hz, old_hz), ("age", age, old_age)):
                    if new != old:
                        table.update_cell(name, column, new, update_width=len(new) > len(old))
        self._topic_rows = rows

    def show_state(self, st: RobotState) -> None:
        self._robot_t = st.t
        view = self.query_one(WarehouseMapView)
        view.set_geometry(self.services.gateway.map_geometry())
        view.set_fleet(self.map_actions.others())  # a fleet's, at its watch's pace
        view.show(st)
        panel = self.query_one("#robot", Static)
        self._robot_text = show_text(panel, robot_text(st), getattr(self, "_robot_text", None))
        gauge = self.query_one("#battery", BatteryGauge)
        if st.battery is None:
            gauge.show_absent()
        else:
            b = st.battery
            gauge.show(b.percentage, b.voltage, b.current, b.charging)

    def _show_events(self) -> None:
        table = self.query_one("#events", DataTable)
        table.clear()
        for ev in reversed(self.app.recent_events[-EVENT_ROWS:]):
            table.add_row(f"{ev.t:.1f}", Text(ev.kind), Text(escape_controls(ev.message)))

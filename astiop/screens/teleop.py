"""Teleop: keys drive vx, vy, ωz; the inverse kinematics shows the four wheel speeds.

Terminals send no key-release events, so each key press commands motion for half a second:
holding a key repeats it, letting go lets the command lapse.
"""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import Screen
from textual.widgets import Footer, Header, Static

from astiop.sim.kinematics import inverse_kinematics
from astiop.sim.state import SimState
from astiop.widgets.gauges import WheelBars
from astiop.widgets.warehouse_map import WarehouseMapView

STEPS = (0.1, 0.2, 0.4, 0.8)


class TeleopScreen(Screen):
    BINDINGS = [
        Binding("w", "drive(1, 0, 0)", "fwd"),
        Binding("s", "drive(-1, 0, 0)", "back"),
        Binding("a", "drive(0, 1, 0)", "left"),
        Binding("d", "drive(0, -1, 0)", "right"),
        Binding("q", "drive(0, 0, 1)", "turn ⟲"),
        Binding("e", "drive(0, 0, -1)", "turn ⟳"),
        Binding("space", "halt", "stop"),
        Binding("plus,equals_sign", "speed(1)", "faster"),
        Binding("minus", "speed(-1)", "slower"),
    ]

    def __init__(self):
        super().__init__()
        self.step = 1
        self.command = (0.0, 0.0, 0.0)

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        with Vertical(id="teleop-grid"):
            yield WarehouseMapView(self.app.services.store.warehouse)
            with Vertical():
                yield Static(id="teleop-help", classes="panel")
                yield WheelBars(id="wheels", classes="panel")
                yield Static(id="teleop-state", classes="panel")
        yield Footer()

    def on_screen_resume(self) -> None:
        # on first show too; locations may have changed on the Locations screen
        self.query_one(WarehouseMapView).set_locations(
            [(loc.x, loc.y) for loc in self.app.services.store.list_locations()]
        )

    def on_mount(self) -> None:
        self._show_help()
        self.query_one(WheelBars).show((0.0, 0.0, 0.0, 0.0))
        if self.app.state is not None:
            self.show_state(self.app.state)

    def _show_help(self) -> None:
        v = STEPS[self.step]
        self.query_one("#teleop-help", Static).update(
            f"[b]teleop[/]  w/s forward/back  a/d left/right  q/e turn  space stop\n"
            f"speed step [b]{v:.1f} m/s[/], turn {2 * v:.1f} rad/s  (+/- to change)\n"
            "a command lapses 0.5 s after the last key press"
        )

    def action_speed(self, delta: int) -> None:
        self.step = min(max(self.step + delta, 0), len(STEPS) - 1)
        self._show_help()

    def action_drive(self, fx: int, fy: int, fw: int) -> None:
        v = STEPS[self.step]
        self.command = (fx * v, fy * v, fw * 2 * v)
        vx, vy, wz = self.command
        cmd = (
            f"ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist "
            f'"{{linear: {{x: {vx}, y: {vy}}}, angular: {{z: {wz}}}}}"'
        )
        result = self.app.services.graph.run(cmd, confirm=lambda _c: True)  # the key is consent
        if not result.executed:
            self.notify(result.reason, severity="warning")
        self.query_one(WheelBars).show(inverse_kinematics(vx, vy, wz))

    def action_halt(self) -> None:
        self.command = (0.0, 0.0, 0.0)
        self.app.services.graph.run("ros2 service call /stop std_srvs/srv/Trigger")
        self.query_one(WheelBars).show((0.0, 0.0, 0.0, 0.0))

    def show_state(self, st: SimState) -> None:
        self.query_one(WarehouseMapView).show(st)
        self.query_one(WheelBars).show(st.wheel_speeds)
        self.query_one("#teleop-state", Static).update(
            f"state {st.state}  mode {st.mode}\nx {st.x:.2f}  y {st.y:.2f}  "
            f"v ({st.vx:+.2f}, {st.vy:+.2f}) m/s  ω {st.wz:+.2f} rad/s"
            + (f"\n[red]fault: {st.fault}[/]" if st.fault else "")
        )

"""Teleop: keys drive vx, vy, ωz; the inverse kinematics shows the four wheel speeds.

Terminals send no key-release events, so each key press commands motion for half a second:
holding a key repeats it, letting go lets the command lapse. Every press goes to the robot on
the screen's sender thread, in order, never on the UI thread, so a slow robot cannot freeze the
screen or delay E-STOP; a worker per press waits for it and reports a refusal.
"""

from __future__ import annotations

from concurrent.futures import CancelledError, Future, ThreadPoolExecutor

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.widgets import Footer, Header, Static

from astiop.screens.base import ConsoleScreen
from astiop.screens.messages import RobotStateSampled
from astiop.screens.panel_text import show_text
from astiop.transports.state import RobotState, wheel_speeds
from astiop.widgets.gauges import WheelBars
from astiop.widgets.map_canvas import MapCanvas

STEPS = (0.1, 0.2, 0.4, 0.8)


class TeleopScreen(ConsoleScreen):
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
        self._wheels_shown: tuple[float, ...] | None = None
        self._state_shown: str | None = None
        # one thread sends the presses, in order (a press waits for none of it)
        self._sender = ThreadPoolExecutor(max_workers=1, thread_name_prefix="teleop")
        self._pending: Future | None = None  # the last press handed to the sender

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        with Vertical(id="teleop-grid"):
            yield MapCanvas(self.services.gateway.map_geometry())
            with Vertical():
                yield Static(id="teleop-help", classes="panel")
                yield WheelBars(id="wheels", classes="panel")
                yield Static(id="teleop-state", classes="panel")
        yield Footer()

    def on_screen_resume(self) -> None:
        view = self.query_one(MapCanvas)
        view.set_locations([(loc.x, loc.y) for loc in self.services.store.list_locations()])
        view.set_zones(self.services.store.list_zones())  # where teleop may not go or slows

    def on_mount(self) -> None:
        self._show_help()
        self._show_wheels((0.0, 0.0, 0.0, 0.0))
        self.show_state(self.app.robot_state)

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
        command = (fx * v, fy * v, fw * 2 * v)
        # the robot first: the sender's thread is idle and starts at once (a worker per press
        # starts at the event loop's next turn); the bars are redrawn once it is sent
        self._supersede()  # a press not sent yet gives way to this one: no backlog to drive
        sent = self._pending = self._sender.submit(self.services.gateway.drive, *command)
        self.run_worker(
            lambda: self._report(sent, wheel_speeds(*command)),
            thread=True,
            group="teleop",
            exit_on_error=False,
        )

    def _supersede(self) -> None:
        if self._pending is not None:
            self._pending.cancel()  # only a press still waiting its turn is canceled

    def _report(self, sent: Future, wheels) -> None:
        try:
            result = sent.result()
        except CancelledError:
            return  # a newer press, or the stop, took its place
        self.app.call_from_thread(self._show_wheels, wheels)
        if not result.executed or result.error:
            why = result.reason or result.error
            self.app.call_from_thread(self.notify, why, severity="warning", markup=False)

    def _show_wheels(self, wheels) -> None:
        """Only a change is drawn: each redraw is a layout pass, and a held key repeats."""
        shown = tuple(round(w, 2) for w in wheels)
        if shown != self._wheels_shown:
            self._wheels_shown = shown
            self.query_one(WheelBars).show(wheels)

    def action_halt(self) -> None:
        self._supersede()
        self._show_wheels((0.0, 0.0, 0.0, 0.0))
        # after the presses before it, on the same thread; a zero Twist, not /stop, which a
        # robot may latch until it is released (ctrl+e stops everything)
        sent = self._sender.submit(self.services.gateway.drive, 0.0, 0.0, 0.0)
        self.run_worker(
            lambda: self._halted(sent), thread=True, group="teleop", exit_on_error=False
        )

    def _halted(self, sent: Future) -> None:
        result = sent.result()
        if result.error:
            self.app.call_from_thread(self.notify, result.error, severity="error", markup=False)

    def on_unmount(self) -> None:
        super().on_unmount()
        self._sender.shutdown(wait=False)

    def on_robot_state_sampled(self, msg: RobotStateSampled) -> None:
        self.show_state(msg.state)

    def show_state(self, st: RobotState) -> None:
        self.query_one(MapCanvas).show(st)
        if st.wheel_speeds is not None:
            self._show_wheels(st.wheel_speeds)
        text = Text(f"state {st.state_word}")
        if st.status:
            text.append(f"  mode {st.status.mode}")
        if st.pose:
            text.append(f"\nx {st.pose.x:.2f}  y {st.pose.y:.2f}")
        if st.velocity:
            vx, vy, wz = st.velocity
            text.append(f"  v ({vx:+.2f}, {vy:+.2f}) m/s  ω {wz:+.2f} rad/s")
        elif st.speed is not None:
            text.append(f"  speed {st.speed:.2f} m/s")
        if st.status and st.status.fault:
            text.append(f"\nfault: {st.status.fault}", style="red")
        panel = self.query_one("#teleop-state", Static)
        self._state_shown = show_text(panel, text, self._state_shown)

"""The Textual console: seven screens over one set of services (store, robot gateway, model).

The robot is reached only through the gateway: its state is sampled off the UI thread and
arrives as `RobotStateSampled`; every robot call runs in a worker; the E-STOP key is handled
off the UI thread and answers any open confirmation with "no".
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path
from typing import Any

from textual.app import App, SystemCommand
from textual.binding import Binding
from textual.screen import Screen
from textual.worker import Worker, WorkerState

from astiop.agent.models.specs import LLMEndpoint, open_endpoint
from astiop.config import Settings
from astiop.robot.factory import make_robot_gateway, make_sim_gateway
from astiop.robot.fleet_watch import FleetRow, FleetWatch, control_of, row_from
from astiop.robot.gateway import RobotGateway
from astiop.robot.sampler import StateSampler
from astiop.ros2.render import goto_command
from astiop.screens import control
from astiop.screens.approvals import ApprovalDesk
from astiop.screens.base import robot_name
from astiop.screens.console_palette import ConsolePalette
from astiop.screens.console_recording import ConsoleRecording
from astiop.screens.console_safety import SafetyKeys
from astiop.screens.dashboard import motion_key
from astiop.screens.messages import AlertsFired, RobotStateSampled, TurnFinished
from astiop.screens.registry import SCREENS
from astiop.services import Services
from astiop.store import Store
from astiop.transports.state import RobotState, TopicStat

log = logging.getLogger("astiop.watches")

SAID_HERE = ("watch", "battery_low", "no_progress", "mission_failed", "mission_interrupted")
STILL_HZ = 4.0  # a still robot's sampling: only its clock, scan noise and battery change


class AstiopApp(App):
    TITLE = "astiop"
    CSS_PATH = "app.tcss"
    MODES = {s.mode: s.screen for s in SCREENS}
    camera_pixels: str | None = None  # the camera as sixel or tgp pixels; None: half-block cells
    BINDINGS = [
        Binding("ctrl+e", "estop", "E-STOP", priority=True),
        *(Binding(s.key, f"switch_mode('{s.mode}')", s.title) for s in SCREENS),
        Binding("ctrl+t", "take_control", "Take control / let go", show=False),
        Binding("ctrl+r", "release_estop", "Release e-stop", priority=True),
        Binding("ctrl+q", "quit", "Quit", priority=True),
        # a replay's clock; focused inputs and tables keep these keys
        Binding("space", "replay_toggle", "Pause/play", show=False),
        Binding("left", "replay_step(-1)", "Back 1 s", show=False),
        Binding("right", "replay_step(1)", "On 1 s", show=False),
        Binding("shift+left", "replay_step(-10)", "Back 10 s", show=False),
        Binding("shift+right", "replay_step(10)", "On 10 s", show=False),
        Binding("left_square_bracket", "replay_speed(0)", "Slower", show=False),
        Binding("right_square_bracket", "replay_speed(1)", "Faster", show=False),
    ]

    def __init__(
        self,
        services: Services,
        *,
        sample_hz: float = 10.0,
        confirm_timeout_s: float = 120.0,
        record: Path | None = None,
        fleet: FleetWatch | None = None,
    ):
        super().__init__()
        self.services = services
        self.fleet = fleet  # every robot of a fleet, watched; None: one robot
        if fleet is not None:  # the current robot watched through the console's own gateway
            fleet.adopt(self.current_robot, services.gateway)
        self.record_path = record
        self.sample_hz = sample_hz
        self.robot_state: RobotState = services.gateway.state()
        self.recent_events = services.gateway.events_since(0)[-50:]  # shown at once, not later
        self.topic_stats: list[TopicStat] = []
        self.listeners: list[Any] = []  # screens that take broadcasts
        last = self.recent_events[-1].seq if self.recent_events else 0
        self._approvals = ApprovalDesk(self)  # outside agents' actuations, asked here
        self.safety = SafetyKeys(self, services, fleet, lambda: self.robot_state, confirm_timeout_s)
        self.recording = ConsoleRecording(self, services, fleet, self.refresh_subtitle)
        self.palette = ConsolePalette(
            self, services, self.safety, self.recording, self.goto_location
        )
        self._sampler = StateSampler(
            services.gateway, self._state_sampled, self._sampler_failed, sample_hz, last
        )
        self._motion: tuple = ()  # the last sample's motion_key
        self._watches = _watches(self)  # None on a replay: it happened already

    def on_mount(self) -> None:
        gateway = self.services.gateway
        # what the robot layer could not keep or read (the store, the latch), on the screen:
        # stderr is the terminal the console draws on
        self._said = _Notices(self)
        logging.getLogger("astiop.robot").addHandler(self._said)
        self.refresh_subtitle()
        gateway.start()
        self.topic_stats = gateway.topic_stats()
        control.start(self)
        self.switch_mode("dashboard")
        self._sampler.start()
        if self.fleet is not None:
            self.fleet.start()
        if self._watches is not None:
            self._watches.start()
        if self.services.gateway.playback is None:  # a replay moves no robot
            self._approvals.start()
        if self.record_path is not None:
            self.recording.start(self.record_path)
        self.run_worker(self._warm_model(), group="warm", exit_on_error=False)
        if not self.services.settings.robot.confirm_actuation:
            self.notify(
                "robot.confirm_actuation is false: actuating commands run without asking",
                title="confirmation is off",
                severity="warning",
                timeout=30,
            )

    async def _warm_model(self) -> None:
        """The embedded model's prompts for this robot, evaluated before the first question."""
        from astiop.agent.warm import warm

        s = self.services
        if s.gateway.playback is not None:
            return  # a replay asks no model until asked
        try:
            took = await warm(s.endpoint, s.gateway, s.store, s.settings.llm.mode)
        except Exception as exc:  # noqa: BLE001 - the first question says what is wrong
            logging.getLogger("astiop.agent").info("warming the model failed: %s", exc)
            return
        if took is not None and s.store is not None:
            said = f"{s.endpoint.spec.raw}: this robot's prompts evaluated in {took:.1f} s"
            with contextlib.suppress(Exception):  # a read-only or busy store: not worth a word
                s.store.add_event("model", said)

    def on_unmount(self) -> None:
        # The robot and the model are let go whatever fails before (a recording that cannot
        # be finished, a thread that will not stop).
        try:
            self._sampler.halt.set()
            self._approvals.halt.set()
            if self._watches is not None:
                self._watches.halt.set()
            self._sampler.join(2.0)
            if self._watches is not None and self._watches.is_alive():
                self._watches.join(2.0)  # not writing an alert as the store closes
            if self._approvals.is_alive():
                self._approvals.join(2.0)
            if self.recording.recorder is not None:
                self.recording.recorder.stop()
            if self.fleet is not None:
                self.fleet.close()  # every robot's gateway, the current one's too
        finally:
            try:
                if self.fleet is None:
                    self.services.gateway.close()
            finally:
                logging.getLogger("astiop.robot").removeHandler(self._said)
                self.services.endpoint.close()

    def broadcast(self, message_factory) -> None:
        for screen in list(self.listeners):
            screen.post_message(message_factory())

    # -- live state ---------------------------------------------------------------------
    def _state_sampled(self, state, events, stats) -> None:  # the sampler's thread
        self.post_message(RobotStateSampled(state, events, stats))

    def on_alerts_fired(self, msg: AlertsFired) -> None:
        for a in msg.alerts:  # the current robot's own events say contact, faults, E-STOP, goals
            if a["kind"] in SAID_HERE or (a["robot"] and a["robot"] != self.current_robot):
                self.notify(a["message"], title="alert", severity="warning", markup=False)
            if a.get("reaction"):  # a watch that moves the robot: what it did or why not
                self.notify(a["reaction"], title="watch reaction", markup=False)

    def _sampler_failed(self, text: str) -> None:  # the sampler's thread
        self.call_from_thread(self.notify, text, severity="error", markup=False)

    def on_robot_state_sampled(self, msg: RobotStateSampled) -> None:
        self._pace_sampler(msg)
        self.robot_state = msg.state
        if msg.events:  # kept here: a screen not shown when they came still shows them
            self.recent_events = (self.recent_events + msg.events)[-50:]
        if msg.stats is not None:
            self.topic_stats = msg.stats
        for ev in msg.events:
            if ev.severity in ("warning", "error"):
                self.notify(ev.message, severity=ev.severity, title=ev.kind, markup=False)
            elif ev.kind == "robot":  # contact with the robot is back: said as loudly as lost
                self.notify(ev.message, title=ev.kind, markup=False)
        if self.screen_stack and self.screen in self.listeners:  # none while shutting down
            self.screen.post_message(RobotStateSampled(msg.state, msg.events, msg.stats))

    def _pace_sampler(self, msg: RobotStateSampled) -> None:
        """STILL_HZ while two samples in a row show the same robot (`motion_key`) and no
        events, sample_hz as soon as one does not: an idle console drew its clock at 10 Hz,
        most of its CPU."""
        key = motion_key(msg.state)
        still = key == self._motion and not msg.events
        self._motion = key
        hz = min(STILL_HZ, self.sample_hz) if still else self.sample_hz
        self._sampler.pace(hz)

    def on_turn_finished(self, msg: TurnFinished) -> None:
        self.broadcast(lambda: TurnFinished(msg.result, msg.model))

    @property
    def current_robot(self) -> str:
        """The robot Dashboard, Chat, Teleop and Locations act on, by its fleet name."""
        return robot_name(self.services, self.fleet)

    def fleet_rows(self) -> list[FleetRow]:
        if self.fleet is not None:
            return self.fleet.rows()
        gateway = self.services.gateway
        make = gateway.profile.make if gateway.profile else ""
        namespace = self.services.settings.robot.namespace
        st = self.robot_state
        row = row_from(self.current_robot, namespace, make, st, st.lost_s or 0.0)
        return [replace(row, control=control_of(gateway))]

    def refresh_subtitle(self) -> None:
        robot = self.services.gateway.label
        if self.fleet is not None:  # never the wrong robot: its name on every screen
            robot = f"{self.current_robot} ({robot})"
        rec = "  ● REC" if self.recording.recorder is not None else ""
        held = control.words(self.services.gateway)
        self.sub_title = f"robot: {robot}{held}  model: {self.services.endpoint.spec.raw}{rec}"

    # -- a replay's clock --------------------------------------------------------------------
    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action.startswith("replay_"):
            return self.services.gateway.playback is not None
        return True

    def action_replay_toggle(self) -> None:
        self.services.gateway.playback.toggle()

    def action_replay_step(self, seconds: int) -> None:
        self.services.gateway.playback.step(seconds)

    def action_replay_speed(self, up: int) -> None:
        self.services.gateway.playback.faster(bool(up))

    def goto_location(self, name: str) -> None:
        """Drive to a named location: the same y/n as every actuation, off the UI thread."""
        cmd = goto_command(name)
        self.run_worker(lambda: self._goto(cmd), thread=True, group="goto", exit_on_error=False)

    def goto_point(self, x: float, y: float, theta: float | None = None) -> None:
        """Drive to a point of the map (a click; a drag gives `theta`): the command the rules
        plan for a typed "go to x, y" on this robot, then the same path as a named place's."""
        from astiop.agent.intent import Intent
        from astiop.agent.rules import command_for

        goal = Intent("navigate", xy=(x, y), theta=theta)
        cmd = command_for(goal, self.services.gateway.profile)
        if cmd is None:
            self.notify("this robot has no way to take a goal", severity="error")
            return
        self.run_worker(lambda: self._goto(cmd), thread=True, group="goto", exit_on_error=False)

    def _goto(self, cmd: str) -> None:
        result = self.services.gateway.run(
            cmd, confirm=self.safety.confirm_from_thread, source="console"
        )
        values = result.values or {}
        if result.executed and values.get("success"):
            self.call_from_thread(self.notify, values["message"], markup=False)
        else:
            why = result.reason or result.error or values.get("message", "refused")
            self.call_from_thread(self.notify, why, severity="error", markup=False)

    # -- the bindings' actions, done by the app's helpers ----------------------------------
    def action_estop(self) -> None:
        self.safety.estop()

    def action_release_estop(self) -> None:
        self.safety.release_estop()

    def action_take_control(self) -> None:
        control.take_over(self)

    def get_system_commands(self, screen: Screen) -> Iterable[SystemCommand]:
        yield from super().get_system_commands(screen)
        yield from self.palette.commands()

    # -- one handler for every worker's failure --------------------------------------------
    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        self.worker_failed(event.worker)

    def worker_failed(self, worker: Worker) -> None:
        if worker.state == WorkerState.ERROR:
            self.notify(
                f"{worker.name or worker.group}: {type(worker.error).__name__}: {worker.error}",
                severity="error",
                title="error",
                markup=False,
            )


def make_app(
    settings: Settings,
    store: Store,
    *,
    gateway: RobotGateway | None = None,
    endpoint: LLMEndpoint | None = None,
    sim: Any = None,
    realtime: bool = True,
    sample_hz: float = 10.0,
    confirm_timeout_s: float = 120.0,
    record: Path | None = None,
    fleet: FleetWatch | None = None,
) -> AstiopApp:
    """Build the console from its services; the CLI and the tests both come through here.

    `sim` hands a prepared simulator to the sim backend (tests: seeded and paused).
    """
    if gateway is None:
        if settings.robot.backend == "sim":
            gateway = make_sim_gateway(settings, store, realtime=realtime, sim=sim, who="console")
        else:
            # a fleet's robots were found on a settled graph: nothing more to wait for
            gateway = make_robot_gateway(
                settings, store, realtime=True, who="console", discover=fleet is None
            )
    endpoint = endpoint or open_endpoint(
        settings.llm.model,
        threads=settings.llm.threads,
        n_ctx=settings.llm.context,
        timeout_s=settings.llm.timeout_s,
        vision=settings.llm.marks_vision(settings.llm.model),
    )
    return AstiopApp(
        Services(settings, store, gateway, endpoint),
        sample_hz=sample_hz,
        confirm_timeout_s=confirm_timeout_s,
        record=record,
        fleet=fleet,
    )


class _Notices(logging.Handler):
    """The robot layer's logged errors as the console's notifications (notify is thread-safe:
    it posts a message)."""

    def __init__(self, app: App):
        super().__init__(logging.WARNING)
        self.app = app

    def emit(self, record: logging.LogRecord) -> None:
        self.app.notify(record.getMessage(), severity="error", title="robot", markup=False)


def _watches(app: AstiopApp):
    """The watches and built-in alerts, on a thread of their own (none on a replay): the
    console's robot evaluated as soon as a reading they read arrives, not at the Dashboard's
    drawing rate; a fleet's every robot at the settings' rate."""
    from astiop.watches.runner import FleetWatching, WatchRunner, make_evaluator

    s, fleet = app.services, app.fleet
    if s.gateway.playback is not None:
        return None
    if fleet is not None:
        fired = lambda alerts: app.post_message(AlertsFired(alerts))  # noqa: E731
        return FleetWatching(lambda: dict(fleet.gateways), s.store, s.settings, fired)
    ev = make_evaluator(s.gateway, s.store, s.settings)
    return WatchRunner(
        s.gateway,
        ev,
        on_alert=lambda alert: app.post_message(AlertsFired([alert])),
        report=lambda text: log.info("watches not evaluated: %s", text),
        hz=s.settings.watches.hz,
    )

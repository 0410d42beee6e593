"""The Textual console: six screens over one set of services (store, robot, model)."""

from __future__ import annotations

import contextlib
import threading
from dataclasses import dataclass

from textual.app import App
from textual.binding import Binding
from textual.css.query import NoMatches
from textual.worker import Worker, WorkerState

from astiop.agent.specs import LLMEndpoint, open_endpoint
from astiop.config import Settings
from astiop.robot.factory import make_robot_graph, make_sim_graph
from astiop.robot.graph import RobotGraph
from astiop.robot.validation import Checked
from astiop.screens.bench import BenchScreen
from astiop.screens.chat import ChatScreen
from astiop.screens.dashboard import DashboardScreen
from astiop.screens.locations import LocationsScreen
from astiop.screens.logs import LogsScreen
from astiop.screens.modals import ConfirmModal
from astiop.screens.teleop import TeleopScreen
from astiop.sim.runner import SimRunner
from astiop.sim.simulator import Simulator
from astiop.sim.state import SimState
from astiop.store import Store


@dataclass
class Services:
    settings: Settings
    store: Store
    graph: RobotGraph
    endpoint: LLMEndpoint
    sim: Simulator | None
    runner: SimRunner | None


class AstiopApp(App):
    TITLE = "astiop"
    CSS_PATH = "app.tcss"
    MODES = {
        "dashboard": DashboardScreen,
        "chat": ChatScreen,
        "logs": LogsScreen,
        "locations": LocationsScreen,
        "teleop": TeleopScreen,
        "bench": BenchScreen,
    }
    BINDINGS = [
        Binding("ctrl+e", "estop", "E-STOP", priority=True),
        Binding("f1", "switch_mode('dashboard')", "Dashboard"),
        Binding("f2", "switch_mode('chat')", "Chat"),
        Binding("f3", "switch_mode('logs')", "Logs"),
        Binding("f4", "switch_mode('locations')", "Locations"),
        Binding("f5", "switch_mode('teleop')", "Teleop"),
        Binding("f6", "switch_mode('bench')", "Bench"),
        Binding("ctrl+r", "release_estop", "Release e-stop", priority=True),
        Binding("ctrl+q", "quit", "Quit", priority=True),
    ]

    def __init__(self, services: Services, *, sample_hz: float = 10.0):
        super().__init__()
        self.services = services
        self.sample_hz = sample_hz
        self.state: SimState | None = services.sim.snapshot() if services.sim else None
        self.last_turn = None
        self._event_seq = 0

    def on_mount(self) -> None:
        self.sub_title = (
            f"robot: {self.services.graph.backend.name}  model: {self.services.endpoint.spec.raw}"
        )
        self.switch_mode("dashboard")
        if self.services.runner is not None:
            self.services.runner.start()
        self.set_interval(1.0 / self.sample_hz, self.sample)

    def on_unmount(self) -> None:
        if self.services.runner is not None:
            self.services.runner.stop()
        self.services.endpoint.close()

    # -- live state ---------------------------------------------------------------------
    def sample(self) -> None:
        sim = self.services.sim
        if sim is None or not self.screen_stack:
            return
        self.state = sim.snapshot()
        if self.state.event_seq != self._event_seq:
            events = sim.events_since(self._event_seq)
            self._event_seq = self.state.event_seq
            self.run_worker(lambda: self._store_events(events), thread=True, group="events")
            for ev in events:
                if ev.severity in ("warning", "error"):
                    self.notify(ev.message, severity=ev.severity, title=ev.kind)
        show = getattr(self.screen, "show_state", None)
        if show is not None:
            with contextlib.suppress(NoMatches):  # a screen still composing its widgets
                show(self.state)

    def _store_events(self, events) -> None:
        for ev in events:
            self.services.store.add_event(ev.kind, ev.message, severity=ev.severity, sim_t=ev.t)

    # -- safety -------------------------------------------------------------------------
    def action_estop(self) -> None:
        self.services.graph.estop()
        self.notify(
            "E-STOP engaged: all motion stopped. ctrl+r releases it.",
            severity="error",
            title="E-STOP",
        )

    def action_release_estop(self) -> None:
        if not self.services.graph.e_stopped:
            self.notify("The e-stop is not engaged.")
            return

        def done(ok: bool | None) -> None:
            if ok:
                self.services.graph.release_estop()
                self.notify("E-stop released.")

        self.push_screen(ConfirmModal("Release the e-stop? The robot may move again."), done)

    def confirm_from_thread(self, checked: Checked, timeout_s: float = 120.0) -> bool:
        """The graph's confirmation hook, called from a worker thread: ask with a modal."""
        answer: list[bool] = []
        ready = threading.Event()

        def ask() -> None:
            def done(ok: bool | None) -> None:
                answer.append(bool(ok))
                ready.set()

            self.push_screen(
                ConfirmModal(f"Run this command? It moves the robot.\n\n{checked.text}"), done
            )

        self.call_from_thread(ask)
        ready.wait(timeout_s)
        return bool(answer and answer[0])

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        if event.state == WorkerState.ERROR:
            self.notify(
                f"{event.worker.name}: {event.worker.error}", severity="error", title="error"
            )


def make_app(
    settings: Settings,
    store: Store,
    *,
    graph: RobotGraph | None = None,
    endpoint: LLMEndpoint | None = None,
    sim: Simulator | None = None,
    realtime: bool = True,
    sample_hz: float = 10.0,
) -> AstiopApp:
    """Build the console from its services; the CLI and the tests both come through here."""
    runner = None
    if graph is None:
        if settings.robot.backend == "sim":
            sim = sim or Simulator(seed=settings.sim.seed, v_max=settings.robot.max_linear_speed)
            graph = make_sim_graph(settings, store, realtime=realtime, sim=sim)
        else:
            graph = make_robot_graph(settings, store, realtime=True)
    sim = sim or getattr(graph.backend, "sim", None)
    if sim is not None and realtime:
        runner = SimRunner(sim, speed=settings.sim.speed)
    endpoint = endpoint or open_endpoint(
        settings.llm.model,
        threads=settings.llm.threads,
        n_ctx=settings.llm.context,
        timeout_s=settings.llm.timeout_s,
    )
    return AstiopApp(Services(settings, store, graph, endpoint, sim, runner), sample_hz=sample_hz)

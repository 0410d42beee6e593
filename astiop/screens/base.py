"""What every console screen shares: broadcasts from the app, and one place for worker errors."""

from __future__ import annotations

from textual.app import App
from textual.screen import Screen
from textual.worker import Worker

from astiop.robot.fleet_watch import FleetWatch
from astiop.services import Services


def robot_name(services: Services, fleet: FleetWatch | None) -> str:
    """The robot Dashboard, Chat, Teleop and Locations act on, by its fleet name."""
    namespace = services.settings.robot.namespace
    for name, ns, _ in fleet.robots if fleet is not None else ():
        if ns == namespace:
            return name
    return namespace.strip("/") or "this robot"


def services_of(app: App) -> Services:
    """The app's services, typed (the app is AstiopApp; Textual types it App)."""
    return app.services  # type: ignore[attr-defined]


class ConsoleScreen(Screen):
    @property
    def services(self) -> Services:
        return services_of(self.app)

    def on_mount(self) -> None:
        self.app.listeners.append(self)
        playback = self.services.gateway.playback
        if playback is not None:  # a replay: where it is, on every screen
            from astiop.widgets.replay_bar import ReplayBar

            self.mount(ReplayBar(playback))

    def on_unmount(self) -> None:
        if self in self.app.listeners:
            self.app.listeners.remove(self)

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        # a screen's worker reports here, not to the App: send it to the one handler
        self.app.worker_failed(event.worker)

"""The console's session recording (the palette's "Start/Stop recording", `--record`): one
MCAP file at a time, the header saying so while it runs; a helper the app holds."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from pathlib import Path

from textual.app import App

from astiop.recording import RecordingError, SessionRecorder, default_path
from astiop.robot.fleet_watch import FleetWatch
from astiop.services import Services


class ConsoleRecording:
    """`changed` is called when a recording starts or ends (the app redraws its header)."""

    def __init__(
        self,
        app: App,
        services: Services,
        fleet: FleetWatch | None,
        changed: Callable[[], None],
    ) -> None:
        self.app = app
        self.services = services
        self.fleet = fleet
        self.changed = changed
        self.recorder: SessionRecorder | None = None

    def start(self, path: Path | None = None) -> None:
        if self.recorder is not None:
            return
        store = self.services.store
        path = path or default_path(store.path.parent)
        try:
            said = partial(self.app.notify, severity="error", title="recording", markup=False)
            fleet = self.fleet
            recorder = SessionRecorder(
                path,
                self.services.gateway,
                store,
                on_error=said,
                fleet=fleet.names if fleet else None,
                gateway_of=fleet.gateway_of if fleet else None,
            )
            self.recorder = recorder.start()
        except RecordingError as exc:
            self.app.notify(str(exc), severity="error", title="recording", markup=False)
            return
        self.changed()
        self.app.notify(f"recording to {path}", title="recording", markup=False)

    def stop(self) -> None:
        if self.recorder is None:
            return
        recorder, self.recorder = self.recorder, None
        try:
            counts = recorder.stop()
        except RecordingError as exc:  # the file could not be finished: said, not raised
            self.changed()
            self.app.notify(str(exc), severity="error", title="recording", markup=False)
            return
        self.changed()
        self.app.notify(
            f"{recorder.path}: {sum(counts.values())} messages",
            title="recording saved",
            markup=False,
        )

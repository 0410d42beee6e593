"""The console's command palette (ctrl+p): its own commands beside Textual's, each a second way
to a key; a helper the app holds and asks for them."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from functools import partial

from textual.app import App, SystemCommand

from astiop.screens import control, mission_commands
from astiop.screens.chat import ChatScreen
from astiop.screens.console_recording import ConsoleRecording
from astiop.screens.console_safety import SafetyKeys
from astiop.screens.logs import LogsScreen
from astiop.screens.registry import SCREENS
from astiop.services import Services


class ConsolePalette:
    """`goto` drives to a named location after the y/n (the app's, as the Locations screen's)."""

    def __init__(
        self,
        app: App,
        services: Services,
        safety: SafetyKeys,
        recording: ConsoleRecording,
        goto: Callable[[str], None],
    ) -> None:
        self.app = app
        self.services = services
        self.safety = safety
        self.recording = recording
        self.goto = goto

    def commands(self) -> Iterable[SystemCommand]:
        """The console's own commands, after Textual's (ctrl+p)."""
        yield SystemCommand("E-STOP", "Stop all motion now (ctrl+e)", self.safety.estop)
        # every screen's key has a second way here: a browser or a tablet may lack F-keys
        for s in SCREENS:
            yield SystemCommand(
                f"Screen: {s.title}", f"Show the {s.mode} screen ({s.key})",
                partial(self.app.switch_mode, s.mode),
            )  # fmt: skip
        yield from mission_commands.palette(self.app)
        yield SystemCommand(
            "Release the E-STOP",
            "Let the robot move again, after a y/n (ctrl+r)",
            self.safety.release_estop,
        )
        llm = self.services.settings.llm
        for spec in dict.fromkeys([llm.model, "rules", "embedded", *llm.endpoints]):
            yield SystemCommand(
                f"Model: {spec}",
                "Answer in Chat with this model",
                partial(self._in_chat, "model", spec),
            )
        for mode in ("tool", "command"):
            yield SystemCommand(
                f"Reply mode: {mode}",
                "How the model writes its plan",
                partial(self._in_chat, "mode", mode),
            )
        for loc in self.services.store.list_locations():
            yield SystemCommand(
                f"Go to {loc.name}",
                f"Drive to ({loc.x:.1f}, {loc.y:.1f}) after a y/n",
                partial(self.goto, loc.name),
            )
        lease = self.services.gateway.lease
        if lease is not None:  # ctrl+t's second way: a browser never hands ctrl+t to a page
            title = "Let go of control" if lease.held else "Take control"
            yield SystemCommand(
                f"{title} of {lease.name}",
                "Asked first (ctrl+t)",
                partial(control.take_over, self.app),
            )
        if self.recording.recorder is None:
            yield SystemCommand(
                "Start recording",
                "The session as MCAP, under the data dir's sessions/",
                self.recording.start,
            )
        else:
            yield SystemCommand(
                "Stop recording", f"Close {self.recording.recorder.path}", self.recording.stop
            )
        for fmt in ("csv", "json"):
            yield SystemCommand(
                f"Export logs as {fmt.upper()}",
                "Interactions and events, to a file",
                partial(self._export_logs, fmt),
            )

    def _in_chat(self, what: str, value: str) -> None:
        self.app.switch_mode("chat")

        def apply() -> None:
            chat = self.app.screen
            if not isinstance(chat, ChatScreen):
                return
            if what == "model":
                chat.switch_model(value)
            else:
                chat.switch_reply_mode(value)

        self.app.call_after_refresh(apply)

    def _export_logs(self, fmt: str) -> None:
        self.app.switch_mode("logs")

        def export() -> None:
            if isinstance(self.app.screen, LogsScreen):
                self.app.screen.action_export(fmt)

        self.app.call_after_refresh(export)

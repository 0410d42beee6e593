"""The console's command palette (ctrl+p): its own commands beside Textual's, each a second way
to a key; a mixin of the app."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from functools import partial
from typing import TYPE_CHECKING, Any, Protocol

from textual.app import SystemCommand
from textual.screen import Screen

from astiop.recording import SessionRecorder
from astiop.screens import mission_commands
from astiop.screens.chat import ChatScreen
from astiop.screens.logs import LogsScreen
from astiop.screens.registry import SCREENS
from astiop.services import Services


class PaletteHost(Protocol):
    """What `ConsolePalette` needs of the app it is mixed into."""

    services: Services
    recorder: SessionRecorder | None

    @property
    def screen(self) -> Screen: ...

    def get_system_commands(self, screen: Screen) -> Iterable[SystemCommand]: ...

    def switch_mode(self, mode: str) -> Any: ...

    def call_after_refresh(self, callback: Callable[..., Any], *args: Any) -> bool: ...

    def action_estop(self) -> None: ...

    def action_release_estop(self) -> None: ...

    def action_take_control(self) -> None: ...

    def goto_location(self, name: str) -> None: ...

    def start_recording(self, path: Any = None) -> None: ...

    def stop_recording(self) -> None: ...


if TYPE_CHECKING:
    _Host = PaletteHost
else:
    _Host = object


class ConsolePalette(_Host):
    def get_system_commands(self, screen) -> Iterable[SystemCommand]:
        """The console's own commands beside Textual's (ctrl+p)."""
        yield from super().get_system_commands(screen)
        yield SystemCommand("E-STOP", "Stop all motion now (ctrl+e)", self.action_estop)
        # every screen's key has a second way here: a browser or a tablet may lack F-keys
        for s in SCREENS:
            yield SystemCommand(
                f"Screen: {s.title}", f"Show the {s.mode} screen ({s.key})",
                partial(self.switch_mode, s.mode),
            )  # fmt: skip
        yield from mission_commands.palette(self)
        yield SystemCommand(
            "Release the E-STOP",
            "Let the robot move again, after a y/n (ctrl+r)",
            self.action_release_estop,
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
                partial(self.goto_location, loc.name),
            )
        lease = self.services.gateway.lease
        if lease is not None:  # ctrl+t's second way: a browser never hands ctrl+t to a page
            title = "Let go of control" if lease.held else "Take control"
            yield SystemCommand(
                f"{title} of {lease.name}", "Asked first (ctrl+t)", self.action_take_control
            )
        if self.recorder is None:
            yield SystemCommand(
                "Start recording",
                "The session as MCAP, under the data dir's sessions/",
                self.start_recording,
            )
        else:
            yield SystemCommand(
                "Stop recording", f"Close {self.recorder.path}", self.stop_recording
            )
        for fmt in ("csv", "json"):
            yield SystemCommand(
                f"Export logs as {fmt.upper()}",
                "Interactions and events, to a file",
                partial(self._export_logs, fmt),
            )

    def _in_chat(self, what: str, value: str) -> None:
        self.switch_mode("chat")

        def apply() -> None:
            chat = self.screen
            if not isinstance(chat, ChatScreen):
                return
            if what == "model":
                chat.switch_model(value)
            else:
                chat.switch_reply_mode(value)

        self.call_after_refresh(apply)

    def _export_logs(self, fmt: str) -> None:
        self.switch_mode("logs")

        def export() -> None:
            if isinstance(self.screen, LogsScreen):
                self.screen.action_export(fmt)

        self.call_after_refresh(export)

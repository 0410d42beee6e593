"""The Textual console."""

from __future__ import annotations

from textual.app import App, ComposeResult
from textual.widgets import Footer, Header, Static

from astiop import __version__
from astiop.config import Settings
from astiop.store import Store


class AstiopApp(App):
    TITLE = "astiop"
    BINDINGS = [("q", "quit", "Quit")]

    def __init__(self, settings: Settings, store: Store):
        super().__init__()
        self.settings = settings
        self.store = store

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        names = ", ".join(loc.name for loc in self.store.list_locations())
        yield Static(
            f"astiop {__version__}\ndatabase: {self.store.path}\nnamed locations: {names}\n\n"
            "The console's screens are not built yet; use the CLI (astiop --help).",
            id="status",
        )
        yield Footer()


def make_app(settings: Settings, store: Store) -> AstiopApp:
    return AstiopApp(settings, store)

"""Opening the Textual console from the CLI."""

from __future__ import annotations

from astiop.cli.common import CliState


def run_console(st: CliState) -> None:
    from astiop.app import make_app

    app = make_app(st.settings, st.store)
    app.run()

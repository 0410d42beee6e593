"""Opening the Textual console from the CLI."""

from __future__ import annotations

from astiop.cli.common import CliState


def run_console(st: CliState) -> None:
    from astiop.agent.specs import SpecError
    from astiop.app import make_app
    from astiop.cli.common import fail
    from astiop.robot.output import BackendError

    try:
        app = make_app(st.settings, st.store)
    except (SpecError, BackendError) as exc:
        fail(str(exc))
    app.run()

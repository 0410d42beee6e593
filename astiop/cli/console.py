"""Opening the Textual console from the CLI."""

from __future__ import annotations

from pathlib import Path

from astiop.cli.common import CliState


def run_console(st: CliState, record: str | None = None) -> None:
    from astiop.agent.specs import SpecError
    from astiop.app import make_app
    from astiop.cli.common import fail
    from astiop.recording import default_path
    from astiop.robot.output import BackendError

    record_path = None
    if record is not None:
        record_path = Path(record).expanduser() if record else default_path(st.db_path.parent)
    try:
        app = make_app(st.settings, st.store, record=record_path)
    except (SpecError, BackendError) as exc:
        fail(str(exc))
    app.run()

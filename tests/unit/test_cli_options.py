"""The options `astiop` reads before typer parses them are the typer app's own."""

from __future__ import annotations

import typer

from astiop.cli import _VALUED
from astiop.cli.commands import app


def test_the_options_read_ahead_are_the_typer_apps_options_that_take_a_value():
    params = typer.main.get_command(app).params
    valued = {name for p in params if not getattr(p, "is_flag", True) for name in p.opts}
    assert valued == _VALUED
    assert {"--db", "--model", "--record"} <= _VALUED and "--take" not in _VALUED

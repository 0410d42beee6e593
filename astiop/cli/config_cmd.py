"""`astiop config`: where the settings file is and what is in force."""

from __future__ import annotations

import typer

from astiop.cli.common import state
from astiop.config import config_path, to_toml

app = typer.Typer(
    help="Show the settings file's path and the settings in force.", no_args_is_help=True
)


@app.command("path")
def path() -> None:
    """Print the path of the TOML settings file (it need not exist)."""
    typer.echo(str(config_path()))


@app.command("show")
def show(ctx: typer.Context) -> None:
    """Print the settings in force (file, then ASTIOP_* variables, then flags) as TOML."""
    st = state(ctx)
    typer.echo(f"# from {config_path()} + ASTIOP_* + flags; database: {st.db_path}")
    typer.echo(to_toml(st.settings), nl=False)

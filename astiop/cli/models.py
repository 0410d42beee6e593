"""`astiop models`: which model endpoints answer."""

from __future__ import annotations

import asyncio

import typer

from astiop.cli.common import print_json, state


def models(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """List the configured model endpoints, whether each answers, and what it serves."""
    from astiop.agent.models.probe import probe

    settings = state(ctx).settings
    specs = list(dict.fromkeys([settings.llm.model, "rules", "embedded", *settings.llm.endpoints]))

    async def run_all():
        return [r.as_json() for r in await asyncio.gather(*(probe(s) for s in specs))]

    rows = asyncio.run(run_all())
    if as_json:
        print_json(rows)
        return
    for row in rows:
        mark = "ok  " if row["answers"] else "DOWN"
        serves = ", ".join(row["serves"][:5])
        typer.echo(f"{mark} {row['spec']:<40} {serves}  {row['detail']}".rstrip())

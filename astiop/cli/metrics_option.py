"""`--metrics HOST:PORT` and `--metrics-token-file F`, shared by `astiop serve` and `astiop watch
run`: the Prometheus exporter (astiop/metrics.py) started beside the command's own work."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from pathlib import Path

import typer

from astiop.cli.common import CliState, fail
from astiop.cli.mcp import loopback

FLAG = "--metrics-token-file"
ADDRESS = typer.Option(
    None,
    "--metrics",
    metavar="[HOST:]PORT",
    help="Serve Prometheus metrics at http://HOST:PORT/metrics (HOST: the loopback unless given).",
)
TOKEN_FILE = typer.Option(
    None,
    FLAG,
    metavar="F",
    help="Require F's one line (mode 600) as the scrape's bearer token; or set "
    "ASTIOP_METRICS_TOKEN. Needed off the loopback.",
)


def start_metrics(
    st: CliState,
    address: str | None,
    token_file: Path | None,
    robots: Callable[[], Iterable] = lambda: (),
):
    """The exporter's server (None: not asked for); a bad address, token or busy port fails in
    one line before the command starts its work."""
    from astiop.bearer_token import METRICS_TOKEN, TokenError, token_from, where

    if address is None:
        if token_file is not None:
            fail("--metrics-token-file needs --metrics HOST:PORT")
        return None
    from astiop.metrics import AstiopCollector, MetricsServer, parse_address

    try:
        host, port = parse_address(address)
        token = token_from(token_file, os.environ, METRICS_TOKEN, FLAG)
    except (ValueError, TokenError) as exc:
        fail(str(exc))
    os.environ.pop(METRICS_TOKEN, None)  # never handed down to another process
    if not loopback(host) and not token:
        fail(f"--metrics on {host} (not the loopback) needs a token ({where(METRICS_TOKEN, FLAG)})")
    try:
        server = MetricsServer(AstiopCollector(st.store, robots), host, port, token)
    except OSError as exc:
        fail(f"--metrics: cannot listen on {host}:{port}: {exc.strerror or exc}")
    typer.echo(f"metrics at {server.url}", err=True)
    return server

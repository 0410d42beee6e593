"""`--metrics HOST:PORT` (`astiop serve`, `astiop watch run`): Prometheus metrics with the
official client, read when scraped — the robots this process reaches (battery, state, speed,
E-STOP, who controls it, how long unheard) and the journal (commands by verdict, model turns with
their time and tokens, open alerts). Nothing is sampled between scrapes.

Off the loopback a bearer token is required (Prometheus: `authorization: {credentials_file: F}`
in the scrape config)."""

from __future__ import annotations

import hmac
import logging
import socket
import threading
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any
from wsgiref.simple_server import WSGIRequestHandler, WSGIServer, make_server

from prometheus_client import CollectorRegistry, make_wsgi_app
from prometheus_client.metrics_core import (
    CounterMetricFamily,
    GaugeMetricFamily,
    Metric,
    SummaryMetricFamily,
)
from prometheus_client.registry import Collector

from astiop.robot.gateway import RobotGateway
from astiop.store import Store
from astiop.transports.state import RobotState

log = logging.getLogger("astiop.metrics")

STATES = ("idle", "navigating", "docking", "charging", "blocked", "e_stopped", "fault", "lost")


@dataclass(frozen=True)
class RobotFigures:
    """One robot as a scrape sees it: `state` None where it could not be read."""

    name: str
    state: RobotState | None
    e_stopped: bool
    holder: str | None  # who controls it (a shared robot's lease), None: no one or not shared


def figures_of(gateway: RobotGateway, name: str = "") -> RobotFigures:
    """The gateway's robot now, named `name` (else its namespace or make); a read that fails
    leaves its readings out, never the scrape."""
    profile = gateway.profile
    name = name or profile.namespace.strip("/") or profile.make
    try:
        state: RobotState | None = gateway.state()
    except Exception as exc:  # noqa: BLE001 - the other metrics still answer
        log.info("metrics: %s not read: %s", name, exc)
        state = None
    lease = gateway.lease
    holder = lease.holder() if lease is not None else None
    return RobotFigures(name, state, gateway.e_stopped, holder.words if holder else None)


class AstiopCollector(Collector):
    """Collected on each scrape: `robots()` gives the robots to report."""

    def __init__(self, store: Store, robots: Callable[[], Iterable[RobotFigures]]):
        self.store = store
        self.robots = robots

    def collect(self) -> Iterator[Metric]:
        yield from self._robot_metrics(list(self.robots()))
        yield from self._journal_metrics()

    def _robot_metrics(self, robots: list[RobotFigures]) -> Iterator[Metric]:
        labels = ["robot"]
        battery = GaugeMetricFamily(
            "astiop_robot_battery_ratio",
            "Battery charge as the robot reports it (0..1)",
            labels=labels,
        )
        volts = GaugeMetricFamily("astiop_robot_battery_volts", "Battery voltage", labels=labels)
        speed = GaugeMetricFamily(
            "astiop_robot_speed_mps",
            "Planar speed the robot reports (odometry, else its status)",
            labels=labels,
        )
        state = GaugeMetricFamily(
            "astiop_robot_state", "1 for the robot's current state", labels=["robot", "state"]
        )
        estop = GaugeMetricFamily(
            "astiop_robot_estop", "1 while the robot is E-stopped or its E-STOP is latched",
            labels=labels,
        )  # fmt: skip
        unheard = GaugeMetricFamily(
            "astiop_robot_unheard_seconds", "How long the robot has not been heard (0: heard)",
            labels=labels,
        )  # fmt: skip
        holder = GaugeMetricFamily(
            "astiop_robot_controlled", "1 while someone holds the robot's lease",
            labels=["robot", "holder"],
        )  # fmt: skip
        for robot in robots:
            name = [robot.name]
            estop.add_metric(name, float(robot.e_stopped))
            if robot.holder is not None:
                holder.add_metric([robot.name, robot.holder], 1.0)
            s = robot.state
            if s is None:
                continue
            unheard.add_metric(name, s.lost_s or 0.0)
            word = s.state_word
            for known in sorted({*STATES, word}):
                state.add_metric([robot.name, known], float(known == word))
            if s.battery is not None:
                battery.add_metric(name, s.battery.percentage)
                volts.add_metric(name, s.battery.voltage)
            if s.speed is not None:
                speed.add_metric(name, s.speed)
        yield from (battery, volts, speed, state, estop, unheard, holder)

    def _journal_metrics(self) -> Iterator[Metric]:
        store = self.store
        commands = CounterMetricFamily(
            "astiop_commands", "Commands by verdict: refused, executed or not executed",
            labels=["verdict"],
        )  # fmt: skip
        for verdict, count in sorted(store.command_verdicts().items()):
            commands.add_metric([verdict], count)
        turns = CounterMetricFamily(
            "astiop_turns", "Model turns by outcome", labels=["model", "status"]
        )
        seconds = SummaryMetricFamily(
            "astiop_turn_seconds", "Time of finished model turns", labels=["model"]
        )
        tokens = CounterMetricFamily(
            "astiop_model_tokens", "Tokens by model and kind", labels=["model", "kind"]
        )
        timed: dict[str, int] = {}
        secs: dict[str, float] = {}
        used: dict[tuple[str, str], int] = {}
        for row in store.turn_totals():
            model = row["model"]
            turns.add_metric([model, row["status"]], row["turns"])
            timed[model] = timed.get(model, 0) + int(row["timed"])
            secs[model] = secs.get(model, 0.0) + float(row["seconds"])
            for kind in ("prompt", "completion"):
                used[model, kind] = used.get((model, kind), 0) + int(row[kind])
        for model in sorted(timed):
            seconds.add_metric([model], count_value=timed[model], sum_value=secs[model])
        for (model, kind), count in sorted(used.items()):
            tokens.add_metric([model, kind], count)
        alerts = GaugeMetricFamily(
            "astiop_alerts_open", "Alerts not acknowledged", labels=["robot", "kind"]
        )
        for (robot, kind), count in sorted(store.open_alert_counts().items()):
            alerts.add_metric([robot, kind], count)
        yield from (commands, turns, seconds, tokens, alerts)


class _Quiet(WSGIRequestHandler):
    timeout = 10  # a client that connects and says nothing holds the one thread no longer

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base's name
        """A scrape every few seconds is not news."""


def _guarded(app: Callable, token: str | None) -> Callable:
    """The metrics app behind `Authorization: Bearer <token>` when a token is set."""
    if token is None:
        return app
    expected = f"Bearer {token}".encode()

    def guarded(environ: dict, start_response: Callable) -> Iterable[bytes]:
        given = environ.get("HTTP_AUTHORIZATION", "").encode()
        if not hmac.compare_digest(given, expected):
            start_response("401 Unauthorized", [("WWW-Authenticate", "Bearer")])
            return [b"a bearer token is required\n"]
        return app(environ, start_response)

    return guarded


class _ServerV6(WSGIServer):
    address_family = socket.AF_INET6


class MetricsServer:
    """The exporter's HTTP server on its own thread; `close()` ends it."""

    def __init__(self, collector: Collector, host: str, port: int, token: str | None = None):
        registry = CollectorRegistry()
        registry.register(collector)
        app = _guarded(make_wsgi_app(registry), token)
        # one scrape at a time on one thread: one store connection, kept (a scrape takes ms)
        server = _ServerV6 if ":" in host else WSGIServer
        self.httpd = make_server(host, port, app, server, handler_class=_Quiet)
        self.port = self.httpd.server_port
        shown = f"[{host}]" if ":" in host else host
        self.url = f"http://{shown}:{self.port}/metrics"
        self._thread = threading.Thread(
            target=self.httpd.serve_forever, name="astiop-metrics", daemon=True
        )
        self._thread.start()

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()
        self._thread.join(5)


def parse_address(text: str) -> tuple[str, int]:
    """`HOST:PORT` or `PORT` (the loopback); ValueError with a one-line reason."""
    host, _, port = text.rpartition(":")
    host = host.strip("[]") or "127.0.0.1"
    try:
        number = int(port)
    except ValueError:
        raise ValueError(f"--metrics {text!r}: give HOST:PORT or PORT") from None
    if not 0 <= number <= 65535:
        raise ValueError(f"--metrics {text!r}: the port must be 0-65535")
    return host, number

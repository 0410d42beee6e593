"""`astiop watch list|add|remove|show|run` and `astiop alerts`: the watches kept in the
database, the headless evaluator, and the alerts they and the built-in ones fired."""

from __future__ import annotations

import json
import signal
import threading
import time
from pathlib import Path

import typer

from astiop.cli import metrics_option
from astiop.cli.common import CliState, fail, print_json, state

app = typer.Typer(
    help="Watches: conditions on a robot's readings that raise an alert, said in plain "
    "language ('tell me when the battery is below 20 %') or with options.",
    no_args_is_help=True,
)
FOLLOW_POLL_S = 0.25


def _robot(st: CliState) -> str:
    return st.robot_name or ""


def _watch_or_fail(st: CliState, watch_id: int):
    from astiop.watches.model import Watch

    row = st.store.watch(watch_id)
    if row is None:
        fail(f"no watch {watch_id} (astiop watch list)")
    return Watch.from_row(row)


def _line(w) -> str:
    state_word = "armed" if w.armed else "fired, disarmed"
    said = f"  ({w.said})" if w.said else ""
    return f"{w.id:>4}  {w.robot or '-'}  {w.sentence()}  [{state_word}]{said}"


@app.command("list")
def list_watches(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """List the watches, armed or not."""
    from astiop.watches.model import Watch

    watches = [Watch.from_row(r) for r in state(ctx).store.list_watches()]
    if as_json:
        print_json([w.as_json() for w in watches])
    elif not watches:
        typer.echo("no watches (astiop watch add 'tell me when the battery is below 20 %')")
    for w in [] if as_json else watches:
        typer.echo(_line(w))


@app.command("show")
def show(ctx: typer.Context, watch_id: int, as_json: bool = typer.Option(False, "--json")) -> None:
    """Show one watch and the alerts it fired."""
    st = state(ctx)
    w = _watch_or_fail(st, watch_id)
    fired = [a for a in st.store.list_alerts(limit=10_000) if a["watch_id"] == watch_id]
    if as_json:
        print_json({**w.as_json(), "alerts": fired})
        return
    typer.echo(_line(w))
    for a in fired:
        typer.echo(f"      {_alert_line(a)}")


def _profile(st: CliState):
    """The robot's roles where they are known without reaching it (the simulator's), else
    None: a role the robot lacks is then said by `watch run`."""
    if st.settings.robot.backend != "sim":
        return None
    from astiop.robot.factory import make_sim_gateway

    gateway = make_sim_gateway(st.settings, None)
    try:
        return gateway.profile
    finally:
        gateway.close()


@app.command("add")
def add(
    ctx: typer.Context,
    words: list[str] = typer.Argument(
        None, help="The watch in plain language: 'tell me when the battery is below 20 %'."
    ),
    field: str = typer.Option(
        "", "--field", help="battery (%), speed (m/s), obstacle_distance (m)."
    ),
    below: float | None = typer.Option(None, "--below", help="Fires when the reading is below."),
    above: float | None = typer.Option(None, "--above", help="Fires when the reading is above."),
    hold_s: float = typer.Option(0.0, "--for", help="Only once it has held this long (s)."),
    every: bool = typer.Option(False, "--every", help="Every time, not only once."),
    then: list[str] = typer.Option(
        None, "--then", help="Then move the robot: dock, undock or a place (repeatable)."
    ),
    yes: bool = typer.Option(False, "--yes", help="Approve the --then steps without asking."),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Add a watch: `add tell me when the battery is below 20 %`, or `add --field battery
    --below 20 [--for 5] [--every]`. A reaction that moves the robot (`..., then send it to the
    dock`, or `--then dock`) is asked for approval, then armed."""
    from astiop.agent.watch_turn import checked_steps, steps_from_words
    from astiop.missions.steps import Step
    from astiop.watches.model import Watch, WatchError, validate
    from astiop.watches.words import split_reaction, watch_from_words

    st = state(ctx)
    sentence, reaction = split_reaction(" ".join(words or []).strip())
    if reaction and then:
        fail("say the reaction in words or with --then, not both")
    places = {loc.name: (loc.x, loc.y) for loc in st.store.list_locations()}
    profile = _profile(st)
    try:
        steps = [Step(t) if t in ("dock", "undock") else Step("goto", place=t) for t in then or []]
        steps = checked_steps(steps, places, profile)
        if reaction:
            steps = steps_from_words(reaction, places, profile)
        if sentence:
            if field or below is not None or above is not None:
                fail("say the watch in words or with --field and --below/--above, not both")
            from astiop.agent.intent import resolve_place

            robot = _robot(st)
            watch = watch_from_words(
                sentence, robot, places, lambda said: resolve_place(said, list(places)),
                (robot,) if robot else (),
            )  # fmt: skip
            if watch is None:
                fail(
                    f"'{sentence}' is no watch astiop understands: say 'tell me when the battery "
                    "is below 20 %', 'warn me if anything comes within 0.5 m', or use --field"
                )
        else:
            if not field or (below is None) == (above is None):
                fail("say the watch in words, or --field with one of --below or --above")
            op, threshold = ("<", below) if below is not None else (">", above)
            assert threshold is not None  # one of the two, checked above
            watch = Watch(field, op, threshold, hold_s, "every" if every else "once", _robot(st))
        validate(watch, profile)
        if steps:
            watch = _armed(watch, steps, yes)
    except WatchError as exc:
        fail(f"{exc}; nothing was stored")
    watch_id = st.store.add_watch(**watch.row())
    if as_json:
        print_json(Watch.from_row(st.store.watch(watch_id) or watch.row()).as_json())
    else:
        typer.echo(f"watch {watch_id}: I will tell you when {watch.sentence()}")


def _armed(watch, steps: list, yes: bool):
    """The watch with mission steps as its reaction, approved here by the operator (once)."""
    from astiop.agent.watch_turn import approver, armed, question

    if not yes and not typer.confirm(question(watch, steps), default=False, err=True):
        fail("not approved; nothing was stored")
    return armed(watch, steps, approver("astiop watch add"))


@app.command("remove")
def remove(ctx: typer.Context, watch_id: int) -> None:
    """Remove a watch (its alerts stay)."""
    if not state(ctx).store.remove_watch(watch_id):
        fail(f"no watch {watch_id} (astiop watch list)")
    typer.echo(f"watch {watch_id} removed")


def _alert_line(a: dict) -> str:
    at = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(a["fired_at"]))
    age = a["reading_age_s"]
    aged = f", {age:.2f} s old" if age is not None else ""
    if a["reading"] and a["reading"] in a["message"]:
        reading = f" ({age:.2f} s old)" if age is not None else ""
    else:
        reading = f" ({a['reading']}{aged})" if a["reading"] else ""
    ack = f" — acknowledged by {a['acknowledged_by']}" if a["acknowledged_by"] else ""
    return f"{a['id']:>5}  {at}  {a['robot'] or '-'}  {a['kind']}: {a['message']}{reading}{ack}"


def _say(a: dict, as_json: bool) -> None:
    typer.echo(json.dumps(a, default=str) if as_json else _alert_line(a))


@app.command("run")
def run(
    ctx: typer.Context,
    as_json: bool = typer.Option(False, "--json"),
    metrics: str | None = metrics_option.ADDRESS,
    metrics_token_file: Path | None = metrics_option.TOKEN_FILE,
) -> None:
    """Evaluate the watches and the built-in alerts on the robot, headless, until SIGINT or
    SIGTERM; each new alert is written once to the database and printed (--json: a line each)."""
    from astiop.metrics import figures_of
    from astiop.robot.factory import make_robot_gateway
    from astiop.transports.base import BackendError
    from astiop.watches.runner import WatchRunner, make_evaluator

    st = state(ctx)
    settings = st.settings
    gateways: list = []  # the robot, once reached: what a scrape reads
    exporter = metrics_option.start_metrics(
        st, metrics, metrics_token_file, lambda: [figures_of(g, _robot(st)) for g in gateways]
    )
    try:
        gateway = make_robot_gateway(settings, st.store, realtime=True, who="astiop watch run")
        gateway.start()
    except BackendError as exc:
        fail(str(exc))
    gateways.append(gateway)
    ev = make_evaluator(gateway, st.store, settings, _robot(st))
    runner = WatchRunner(
        gateway,
        ev,
        on_alert=lambda a: _said_with_reaction(a, as_json),
        report=lambda text: typer.echo(f"astiop: {text}", err=True),
        hz=settings.watches.hz,
    )

    def halt(*_) -> None:
        # set from another thread: the handler runs on the main thread, which may hold the
        # event's lock inside `halt.wait` (setting it here could wait on that lock forever)
        threading.Thread(target=runner.halt.set, name="halt").start()

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, halt)
    typer.echo(f"watching {gateway.label} (Ctrl-C to stop)", err=True)
    try:
        runner.run()
    finally:
        if exporter is not None:
            exporter.close()
        gateway.close()


def _said_with_reaction(alert: dict, as_json: bool) -> None:
    _say(alert, as_json)
    if alert.get("reaction") and not as_json:  # JSON carries it in the alert's line
        typer.echo(f"astiop: {alert['reaction']}", err=True)


def alerts(
    ctx: typer.Context,
    follow: bool = typer.Option(False, "--follow", "-f", help="Wait for new ones (Ctrl-C)."),
    last: int = typer.Option(50, "--last", min=1, max=10_000, help="How many to show first."),
    as_json: bool = typer.Option(False, "--json", help="JSON (with --follow: a line each)."),
) -> None:
    """The alerts that watches and the built-in alerts fired, oldest first."""
    store = state(ctx).store
    shown = store.list_alerts(limit=last)
    if as_json and not follow:
        print_json(shown)
        return
    if not shown and not follow:
        typer.echo("no alerts")
    for a in shown:
        _say(a, as_json)
    seen = shown[-1]["id"] if shown else 0
    try:
        while follow:
            time.sleep(FOLLOW_POLL_S)
            for a in store.list_alerts(after_id=seen, limit=10_000):
                _say(a, as_json)
                seen = a["id"]
    except KeyboardInterrupt:
        pass

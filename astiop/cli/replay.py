"""`astiop replay`: a recorded session (MCAP) played back in the console, as if live."""

from __future__ import annotations

from pathlib import Path

import typer

# `astiop serve`'s warm console: its services built (nothing running yet), waits for a tab


def replay(
    ctx: typer.Context,
    file: Path = typer.Argument(..., help="An MCAP recording made by astiop (record, --record)."),
    speed: float = typer.Option(1.0, "--speed", help="Recorded seconds per second: 0.25 to 16."),
    paused: bool = typer.Option(False, "--paused", help="Open paused at the start."),
) -> None:
    """Open the console on a recording: dashboard, map and logs replay it; nothing is sent.

    Keys: space pauses, ←/→ step a second (shift: ten), [ and ] change the speed.
    """
    import tempfile

    from astiop.agent.models.specs import SpecError
    from astiop.app import make_app
    from astiop.cli.common import fail, state
    from astiop.recording import RecordingError
    from astiop.recording.reader import Recording, fleet_of
    from astiop.robot.gateway import RobotGateway
    from astiop.store import Store
    from astiop.transports.base import BackendError
    from astiop.transports.replay.backend import SPEEDS, ReplayBackend

    if not (SPEEDS[0] <= speed <= SPEEDS[-1]):
        fail(f"--speed must be between {SPEEDS[0]:g} and {SPEEDS[-1]:g}")
    if not file.is_file():
        fail(f"{file}: no such recording")
    st = state(ctx)
    with tempfile.TemporaryDirectory(prefix="astiop-replay-") as tmp:
        # the replay's own store: what it shows and records never reaches the operator's
        store = Store(Path(tmp) / "replay.db")
        store.copy_locations_from(st.store)
        try:
            recording = Recording(file)
            robots = fleet_of(recording)
            if robots:  # a fleet's session: the fleet replayed, its first robot current
                settings, fleet = replayed_fleet(
                    st.settings, recording, robots, store, speed, paused
                )
                gateway = fleet.robots[0][2]()
            else:
                backend = ReplayBackend(recording, store=store, speed=speed, paused=paused)
                settings, fleet = st.settings, None
                gateway = RobotGateway(backend, store=store, who="replay")
            app = make_app(settings, store, gateway=gateway, fleet=fleet)
        except (RecordingError, SpecError, BackendError) as exc:
            fail(str(exc))
        app.run()
        store.close()


def replayed_fleet(settings, recording, robots, store, speed: float, paused: bool):
    """The settings of the fleet's first robot, and a watch of every recorded robot."""
    from astiop.robot.fleet_watch import FleetWatch
    from astiop.robot.gateway import RobotGateway
    from astiop.transports.replay.backend import open_fleet_replay

    backends = open_fleet_replay(recording, robots, store=store, speed=speed, paused=paused)

    def settings_for(name: str):
        ns = dict(robots)[name]
        return settings.model_copy(
            update={"robot": settings.robot.model_copy(update={"namespace": ns})}
        )

    gateways = [RobotGateway(b, store=store, who="replay") for b in backends]
    watch = FleetWatch(
        [(name, ns, lambda g=g: g) for (name, ns), g in zip(robots, gateways, strict=True)]
    )
    watch.settings_for = settings_for
    return settings_for(robots[0][0]), watch

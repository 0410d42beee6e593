"""The console's control of a shared robot (robot/lease.py): taken at start when no one holds
it, else the robot is watched; ctrl+t takes it over, asked first (or, held here, lets go of it);
a console whose robot was taken over is told at once and watches from then on."""

from __future__ import annotations

from astiop.screens.base import services_of
from astiop.screens.modals import ConfirmModal


def start(app) -> None:
    """Take control of the current robot if it is free (off the app's thread: a store write)."""
    lease = services_of(app).gateway.lease
    if lease is None:
        return

    def lost(holder) -> None:  # the lease's heartbeat thread
        by = holder.words if holder else "another console"
        app.call_from_thread(_said, app, f"{lease.name} was taken over by {by}: you watch it now")

    lease.on_lost = lost

    def take() -> None:
        try:
            refused = services_of(app).gateway.take_control()
        finally:  # the header says how it ended, even by an error
            app.call_from_thread(app.refresh_subtitle)
        if refused:
            said = f"{refused}: you watch it; ctrl+t takes control"
            app.call_from_thread(_said, app, said)

    app.run_worker(take, thread=True, group="lease", exit_on_error=False)


def _said(app, text: str) -> None:
    app.notify(text, title="control", severity="warning", timeout=15, markup=False)
    app.refresh_subtitle()


def words(gateway) -> str:
    """'' for a robot of this console's own; else whether it is controlled here (before the
    first take is answered, that it is being taken: never WATCHING for a moment)."""
    lease = gateway.lease
    if lease is None:
        return ""
    if lease.held:
        return "  in control"
    return "  WATCHING" if lease.tried else "  taking control…"


def take_over(app) -> None:
    """ctrl+t: control of the current robot taken from whoever has it, once the operator said;
    held here already, let go of (asked too)."""
    gateway = services_of(app).gateway
    lease = gateway.lease
    if lease is None:
        app.notify("This robot is this console's own: there is no control to take.")
        return
    if lease.held:
        _let_go(app, gateway, lease.name)
        return
    holder = lease.other_holder()
    by = f" from {holder.words}; they will be told" if holder else ""
    question = f"Take control of {lease.name}{by}?"

    def done(ok: bool | None) -> None:
        if not ok:
            return

        def take() -> None:
            gateway.take_control(force=True)
            app.call_from_thread(app.notify, f"{lease.name} is controlled from here now.")
            app.call_from_thread(app.refresh_subtitle)

        app.run_worker(take, thread=True, group="lease", exit_on_error=False)

    app.push_screen(ConfirmModal(question), done)


def _let_go(app, gateway, name: str) -> None:
    question = f"Let go of control of {name}? Another operator may then take it; you watch it."

    def done(ok: bool | None) -> None:
        if not ok:
            return

        def let_go() -> None:
            gateway.let_go_of_control()
            app.call_from_thread(app.notify, f"{name} is free: you watch it (ctrl+t takes it).")
            app.call_from_thread(app.refresh_subtitle)

        app.run_worker(let_go, thread=True, group="lease", exit_on_error=False)

    app.push_screen(ConfirmModal(question), done)


def use_robot(app, name: str) -> None:
    """Make `name` the current robot: Dashboard, Chat, Teleop and Locations act on it from now,
    through the gateway the fleet already watches it with; control of it taken if free."""
    from astiop.robot.sampler import StateSampler
    from astiop.screens.messages import CurrentRobotChanged

    if app.fleet is None or name == app.current_robot:
        return
    gateway = app.fleet.gateway_of(name)
    if gateway is None:
        app.notify(f"{name} is not reached yet: it stays {app.current_robot}", severity="error")
        return
    old = app._sampler
    old.halt.set()  # its thread ends at its next tick; its robot stays watched by the fleet
    services = services_of(app)
    services.gateway.watch_lightly(True)  # a row of the fleet's from now
    gateway.watch_lightly(False)
    services.gateway = gateway
    services.settings = app.fleet.settings_for(name)
    app.robot_state = gateway.state()
    app.recent_events = gateway.events_since(0)[-50:]
    last = app.recent_events[-1].seq if app.recent_events else 0
    app._sampler = StateSampler(
        gateway, app._state_sampled, app._sampler_failed, app.sample_hz, last
    )
    app._sampler.start()
    start(app)
    app.refresh_subtitle()
    app.broadcast(lambda: CurrentRobotChanged(name))
    app.notify(f"current robot: {name}", title="fleet")

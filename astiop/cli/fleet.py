"""`astiop fleet`: the robots of the fleet and their state; `astiop estop --all` stops them all.

Each robot is reached as one robot is (its namespace on the ROS 2 domain), all of them at once
in threads of this process."""

from __future__ import annotations

import threading
import time

import typer

from astiop.cli.common import fail, print_json, state

app = typer.Typer(help="The robots of the fleet: their state; one E-STOP for all.")
READ_S = 10.0  # a robot's first pose and battery, or it is said to be silent
STATUS_S = 2.0  # then its state word (a robot with no status of its own: its goal status)


def members(st, on_found=None, settle_s: float | None = None) -> list:
    """The fleet's robots: the settings' list, or every robot namespace on the domain, read
    until the graph has settled (no new robot for `settle_s`); `on_found(robot)` is called as
    each is found (an E-STOP does not wait for the whole graph to stop the first robot)."""
    from astiop.robot.fleet import FleetError, find_robots

    try:
        return find_robots(st.fleet_settings, on_found, settle_s)
    except FleetError as exc:
        fail(str(exc))


def each(robots: list, work) -> dict[str, object]:
    """`work(robot)` for every robot at once; its result or the exception it raised, by name."""
    results: dict[str, object] = {}

    def run(robot) -> None:
        try:
            results[robot.name] = work(robot)
        except Exception as exc:  # noqa: BLE001 - one robot's failure is its own line
            results[robot.name] = exc

    threads = [threading.Thread(target=run, args=(r,), daemon=True) for r in robots]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return results


def read_rows(st, robots: list) -> list:
    """Every robot's row (robot/fleet_watch.py's FleetRow) as it reports now, read at once."""
    from astiop.robot.fleet_watch import FleetRow

    settings = st.fleet_settings
    from astiop.cli.estop import store_softly

    store, _ = store_softly(st)  # its E-STOP latch: a latched robot is shown as held
    found = each(robots, lambda r: _read(settings, r, store))
    return [
        found[r.name]
        if not isinstance(found[r.name], Exception)
        else FleetRow(r.name, r.namespace, error=str(found[r.name]))
        for r in robots
    ]


def _read(settings, robot, store=None):
    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.fleet import robot_settings
    from astiop.robot.fleet_watch import row_of

    gateway = make_robot_gateway(robot_settings(settings, robot.name), store, who="fleet")
    try:
        gateway.start()
        deadline = time.monotonic() + READ_S
        while time.monotonic() < deadline:
            st = gateway.state()
            if st.pose is not None and st.battery is not None:
                deadline = min(deadline, time.monotonic() + STATUS_S)
                if st.status is not None:
                    break
            time.sleep(0.2)
        return row_of(robot.name, robot.namespace, gateway)
    finally:
        gateway.close()


@app.command("list")
def list_cmd(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """Every robot of the fleet with what it reports: state, battery, pose, speed."""
    st = state(ctx)
    robots = members(st)
    rows = [
        {"name": r.name, "namespace": r.namespace, "error": r.error} if r.error else r.as_json()
        for r in read_rows(st, robots)
    ]
    if as_json:
        print_json(rows)
        return
    width = max(len(r["name"]) for r in rows)
    typer.echo(f"{'name':<{width}}  {'state':<10}  {'battery':>7}  {'x':>7}  {'y':>7}  namespace")
    for r in rows:
        if "error" in r:
            typer.echo(f"{r['name']:<{width}}  not reached: {r['error']}")
            continue
        battery = f"{r['battery_percent']:.1f} %" if r["battery_percent"] is not None else "-"
        x = f"{r['x_m']:.2f}" if r["x_m"] is not None else "-"
        y = f"{r['y_m']:.2f}" if r["y_m"] is not None else "-"
        typer.echo(
            f"{r['name']:<{width}}  {r['state']:<10}  {battery:>7}  {x:>7}  {y:>7}  {r['namespace']}"
        )


def estop_all(st) -> None:
    """Every robot of the fleet stopped at once, each through its own zero Twists and stop (or
    its goals cancelled), then the E-STOP latched for every process on this database. A robot it
    could not stop (a hung node, a lost link), or one driven from here that is not on the graph
    now, is named as one that may still be moving, and a keeper stops it when it is heard."""
    from astiop import estop_sql
    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.fleet import FOUND_ONCE_S, robot_settings

    settings = st.fleet_settings
    at = estop_sql.pressed_at()
    results: dict[str, object] = {}
    threads: list[threading.Thread] = []

    def stop(robot) -> list[str]:
        gateway = make_robot_gateway(
            robot_settings(settings, robot.name), None, who="estop --all", discover=False,
            restore_latch=False,
        )  # fmt: skip
        try:
            failures = gateway.estop(at)
            return failures + gateway.settle_estop(settings.robot.ros2_timeout_s)
        finally:
            gateway.close()

    def stop_now(robot) -> None:  # each robot as soon as it is found
        thread = threading.Thread(target=lambda: results.update(each([robot], stop)))
        thread.start()
        threads.append(thread)

    # looked for longer than a listing: on a loaded machine one robot's participant was
    # discovered more than 2 s after another's, and the E-STOP must miss none
    robots = members(st, stop_now, FOUND_ONCE_S)
    recorded = _record_all(st, at)  # after the robots: a database in trouble holds none up
    for thread in threads:
        thread.join()
    unstopped: list[str] = []
    for robot in robots:
        got = results[robot.name]
        if isinstance(got, Exception):
            unstopped.append(robot.name)
            typer.echo(f"{robot.name}: NOT REACHED: {got}", err=True)
        elif got:
            unstopped.append(robot.name)
            typer.echo(f"{robot.name}: stopped with failures: {'; '.join(got)}", err=True)
        else:
            typer.echo(f"{robot.name}: E-STOP engaged")
    for name in _driven_here_not_found(st, robots):
        unstopped.append(name)
        typer.echo(f"{name}: NOT FOUND on the graph now (driven from here before)", err=True)
    if unstopped and settings.robot.backend == "ros2":
        from astiop.cli.estop import keep_on_the_graph

        for name in unstopped:  # each tried again, by a keeper, until it is stopped
            keep_on_the_graph(st, at, name)
        typer.echo(f"MAY STILL BE MOVING: {', '.join(unstopped)}", err=True)
    if recorded:
        typer.echo(f"astiop: {recorded}", err=True)
    typer.echo(f"E-STOP latched for {len(robots)} robots")
    if unstopped or recorded:
        raise typer.Exit(1)


def _record_all(st, at: float) -> str:
    """The press latched for every robot on this database; what went wrong ("")."""
    from astiop.cli.estop import store_softly

    store, why = store_softly(st)
    if store is None:
        return f"not latched in the database: {why}"
    try:
        store.latch_estop("estop --all", at)
    except Exception as exc:  # noqa: BLE001 - full, damaged, locked, read-only
        return f"not latched in the database: {exc}"
    return ""


def _driven_here_not_found(st, robots: list) -> list[str]:
    """Robots of a discovered fleet this database drove (a motion command under its namespace)
    that are not on the graph now: a hung process is not discovered by a new one."""
    from astiop.cli.estop import store_softly

    if st.fleet_settings.fleet.discover != "auto":
        return []  # a listed fleet's robots are all tried, found or not
    store, _ = store_softly(st)
    if store is None:
        return []
    found = {r.namespace.rstrip("/") for r in robots}
    try:
        leased = store.namespaces_driven()
    except Exception:  # noqa: BLE001 - nothing more to name
        return []
    return sorted(
        {ns.strip("/") for ns in leased if ns.rstrip("/") and ns.rstrip("/") not in found}
    )


def release_all(st, yes: bool) -> None:
    """The latch released, and each robot that latches its own stop (/release) let go."""
    from astiop.cli.common import interactive
    from astiop.robot.factory import make_robot_gateway
    from astiop.robot.fleet import robot_settings

    robots = members(st)
    found = {r.namespace for r in robots}
    if st.fleet_settings.fleet.discover == "auto":  # latched, not found on the graph (yet)
        from astiop.config import FleetRobot

        latched = [ns for ns in st.store.latched_robots() if ns not in found]
        robots += [FleetRobot(name=ns.strip("/"), namespace=ns) for ns in latched]
    robots = sorted(robots, key=lambda r: r.name)  # found or only latched, said in one order
    names = ", ".join(r.name for r in robots)
    if not yes:
        if not interactive():
            fail("releasing the E-STOP needs a person to confirm it (or --yes)")
        if not typer.confirm(f"release the E-STOP of {names} (they may move again)?", err=True):
            fail("not released", code=1)
    st.store.release_estop("estop --release --all")
    settings = st.fleet_settings

    def release(robot) -> list[str]:
        # released, not restored: a latch sent again now could reach the robot after /release
        gateway = make_robot_gateway(robot_settings(settings, robot.name), st.store,
                                     who="release", restore_latch=False)  # fmt: skip
        try:
            return gateway.release_estop()
        finally:
            gateway.close()

    results = each(robots, release)
    failed = [f"{n}: {r}" for n, r in results.items() if isinstance(r, Exception) or r]
    typer.echo(f"E-STOP released: {names}")
    if failed:
        fail("; ".join(str(f) for f in failed), code=1)

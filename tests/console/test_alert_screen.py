"""The Alerts screen (F8): open alerts from every process on the database, acknowledged by whom
and when, filtered by robot and kind; `a` acknowledges the selected one."""

from __future__ import annotations

from textual.widgets import DataTable, Select, Static

from astiop.store import Store
from tests.tui_helpers import console, wait_for


def _fire(store, robot: str, kind: str, message: str, n: int) -> int:
    alert_id = store.fire_alert(f"{robot}/{kind}:{n}", robot=robot, kind=kind, message=message)
    assert alert_id is not None
    return alert_id


def _rows(app) -> list[list[str]]:
    table = app.screen.query_one(DataTable)
    return [[str(c) for c in table.get_row_at(i)] for i in range(table.row_count)]


async def test_open_alerts_are_listed_filtered_and_acknowledged_with_a_key(tmp_path):
    app = console(tmp_path)
    store = app.services.store
    low = _fire(store, "astibot_1", "battery_low", "battery low: 18.0 % (below 20 %)", 1)
    stop = _fire(store, "astibot_2", "estop", "E-STOP engaged by ana on bench (pid 7)", 2)
    done = _fire(store, "astibot_2", "fault", "fault reported: left motor overcurrent", 3)
    assert store.acknowledge_alert(done, "bob on desk (pid 9)")
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("f8")
        await wait_for(pilot, lambda: len(_rows(app)) == 2, what="the two open alerts")
        rows = _rows(app)
        assert [r[0] for r in rows] == [str(stop), str(low)]  # newest first
        assert rows[0][3:5] == ["estop", "E-STOP engaged by ana on bench (pid 7)"]
        assert all(r[6] == "open" for r in rows)
        count = app.screen.query_one("#alerts-count", Static)
        assert "2 alerts shown, 2 open" in str(count.render())

        app.screen.query_one("#alerts-state", Select).value = "all"
        await wait_for(pilot, lambda: len(_rows(app)) == 3, what="acknowledged ones too")
        fault = next(r for r in _rows(app) if r[0] == str(done))
        assert fault[6].startswith("bob on desk (pid 9) at ")

        app.screen.query_one("#alerts-robot", Select).value = "astibot_2"
        await wait_for(pilot, lambda: len(_rows(app)) == 2, what="astibot_2's alerts")
        app.screen.query_one("#alerts-kind", Select).value = "estop"
        await wait_for(pilot, lambda: len(_rows(app)) == 1, what="astibot_2's E-STOP")

        app.screen.query_one("#alerts-kind", Select).value = "any"
        app.screen.query_one("#alerts-robot", Select).value = "any"
        app.screen.query_one("#alerts-state", Select).value = "open"
        await wait_for(pilot, lambda: len(_rows(app)) == 2, what="the open ones again")
        app.screen.query_one(DataTable).focus()
        await pilot.press("a")  # the first row: the E-STOP
        await wait_for(pilot, lambda: len(_rows(app)) == 1, what="the E-STOP acknowledged")
        acked = store.alert(stop)
        assert acked["acknowledged_by"].startswith("console on ")
        assert acked["acknowledged_at"] is not None

        other = Store(tmp_path / "console.db")  # another process's alert shows by itself
        try:
            later = _fire(other, "astibot_3", "contact_lost", "contact lost", 4)
        finally:
            other.close()
        await wait_for(pilot, lambda: _rows(app)[0][0] == str(later), what="another's alert")


async def test_a_fleet_console_raises_every_robots_built_in_alerts(tmp_path):
    """Three simulated ASTIbots, astibot_2 current: astibot_3's E-STOP is an alert of its own,
    notified though it is not the robot shown, and listed on the Alerts screen."""
    from tests.console.test_tui_fleet import fleet_console

    app, _fleet, runner = fleet_console(tmp_path)
    runner.start()
    try:
        async with app.run_test(size=(150, 40)) as pilot:
            await wait_for(pilot, lambda: "astibot_3" in app.fleet.gateways, what="astibot_3")
            assert app.fleet.estop("astibot_3") == []
            store = app.services.store

            def stopped() -> list[dict]:
                return [a for a in store.list_alerts() if a["kind"] == "estop"]

            await wait_for(pilot, stopped, what="astibot_3's E-STOP alert")
            (alert,) = stopped()
            assert alert["robot"] == "astibot_3"
            assert alert["message"].startswith("E-STOP engaged")
            await wait_for(
                pilot,
                lambda: (
                    alert["message"]
                    in [n.message for n in app._notifications if n.title == "alert"]
                ),
                what="the notification",
            )
            await pilot.press("f8")
            await wait_for(pilot, lambda: any(r[2] == "astibot_3" for r in _rows(app)))
    finally:
        runner.stop()

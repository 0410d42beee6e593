"""SVG snapshots of every screen at 120x40: seeded, paused sim; no clock; no blinking cursor;
taken once the app is idle, not after a fixed sleep."""

import time

import pytest
from textual.widgets import Input
from textual.worker import WorkerCancelled

from astiop.screens.registry import SCREENS
from astiop.sim.simulator import Simulator
from tests.tui_helpers import console

SIZE = (120, 40)


def scene() -> Simulator:
    sim = Simulator(seed=0)
    sim.add_obstacle("pallet", 16.0, 8.75)
    sim.goto(37.6, 21.0, 0.0, "cps_storage")
    sim.step(12.0)
    return sim


def showing(key: str):
    async def run_before(pilot) -> None:
        await pilot.press(key)
        for _ in range(5):  # a refresh a newer one replaced (exclusive) is cancelled: wait again
            try:
                await pilot.app.workers.wait_for_complete()
                break
            except WorkerCancelled:
                continue
        for field in pilot.app.screen.query(Input):
            field.cursor_blink = False
        await pilot.pause()
        await pilot.wait_for_scheduled_animations()
        await pilot.pause()

    return run_before


@pytest.mark.parametrize("key", [s.key for s in SCREENS if s.mode != "logs"])  # logs: below
def test_screen_snapshots(snap_compare, tmp_path, key):
    app = console(tmp_path, sim=scene())
    assert snap_compare(app, terminal_size=SIZE, run_before=showing(key))


def _history(store) -> None:
    """Two turns and two events at fixed times, as the store records them."""
    t0 = 1_767_000_000.0  # fixed: the snapshot shows these times
    first = store.start_interaction(model="rules", mode="rules", prompt="where is the robot?")
    store.update_interaction(first, started_at=t0, status="done", answer="position x 2.50 m")
    store.add_command(
        first,
        seq=0,
        command="ros2 topic echo /robot_pose --once",
        valid=1,
        kind="read",
        executed=1,
        output="x: 2.5\n",
        source="chat",
    )
    second = store.start_interaction(model="embedded", mode="tool", prompt="leave the dock")
    store.update_interaction(second, started_at=t0 + 60, status="done", answer="undocked")
    store.add_command(
        second,
        seq=0,
        command="ros2 service call /dock std_srvs/srv/Trigger",
        valid=1,
        kind="actuate",
        executed=0,
        reason="refused by the intent gate",
        source="chat",
    )
    store.add_event("goal", "goal 1 accepted: shipping")
    store.add_event("battery", "battery low: 18 %", severity="warning")
    store.db.conn.execute("UPDATE events SET t = ? WHERE kind = 'goal'", [t0 + 30])
    store.db.conn.execute("UPDATE events SET t = ? WHERE kind = 'battery'", [t0 + 90])
    store.db.conn.commit()


def test_logs_snapshot(snap_compare, tmp_path, monkeypatch):
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()
    app = console(tmp_path, sim=Simulator(seed=0))
    _history(app.services.store)
    try:
        logs = next(s.key for s in SCREENS if s.mode == "logs")
        assert snap_compare(app, terminal_size=SIZE, run_before=showing(logs))
    finally:
        monkeypatch.undo()
        time.tzset()

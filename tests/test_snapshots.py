"""SVG snapshots of every screen at 120x40: seeded, paused sim; no clock; no blinking cursor;
taken once the app is idle, not after a fixed sleep."""

import pytest
from textual.widgets import Input

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
        await pilot.app.workers.wait_for_complete()
        for field in pilot.app.screen.query(Input):
            field.cursor_blink = False
        await pilot.pause()
        await pilot.wait_for_scheduled_animations()
        await pilot.pause()

    return run_before


@pytest.mark.parametrize("key", ["f1", "f2", "f4", "f5", "f6"])
def test_screen_snapshots(snap_compare, tmp_path, key):
    app = console(tmp_path, sim=scene())
    assert snap_compare(app, terminal_size=SIZE, run_before=showing(key))


def test_logs_snapshot(snap_compare, tmp_path):
    # a logs screen with no rows: timestamps of real rows would differ run to run
    app = console(tmp_path, sim=Simulator(seed=0))
    assert snap_compare(app, terminal_size=SIZE, run_before=showing("f3"))

"""SVG snapshots of every screen at 120x40: seeded, paused sim; no clock; fixed content."""

import pytest

from astiop.sim.simulator import Simulator
from tests.tui_helpers import console

SIZE = (120, 40)


def scene() -> Simulator:
    sim = Simulator(seed=0)
    sim.add_obstacle("pallet", 16.0, 8.75)
    sim.goto(37.6, 21.0, 0.0, "cps_storage")
    sim.step(12.0)
    return sim


@pytest.mark.parametrize("key", ["f1", "f2", "f4", "f5", "f6"])
def test_screen_snapshots(snap_compare, tmp_path, key):
    app = console(tmp_path, sim=scene())
    assert snap_compare(app, terminal_size=SIZE, press=[key, "wait:300"])


def test_logs_snapshot(snap_compare, tmp_path):
    # a logs screen with no rows: timestamps of real rows would differ run to run
    app = console(tmp_path, sim=Simulator(seed=0))
    assert snap_compare(app, terminal_size=SIZE, press=["f3", "wait:300"])

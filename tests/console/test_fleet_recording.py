"""A fleet's session recorded as one MCAP file (every robot's topics under its namespace, its
events apart) and replayed as a fleet: each robot where it was, on one clock, nothing sent."""

from __future__ import annotations

import math

from textual.widgets import DataTable

from astiop.cli.replay import replayed_fleet
from astiop.config import load_settings
from astiop.recording import SessionRecorder, summary
from astiop.recording.reader import Recording, fleet_of
from astiop.robot.factory import make_safety
from astiop.robot.gateway import RobotGateway
from astiop.ros2.render import goto_command
from astiop.sim.fleet import SimFleet
from astiop.store import Store
from astiop.transports.replay.backend import READ_ONLY, open_fleet_replay
from astiop.transports.simulator.backend import SimBackend
from tests.tui_helpers import wait_for

NAMES = ["astibot_1", "astibot_2"]


def _record(tmp_path):
    """astibot_2 driven toward shipping and astibot_1 E-STOPPED, recorded from the first;
    astibot_2 found a moment after the recording began (as a fleet's console finds robots)."""
    settings = load_settings({"llm": {"model": "rules"}}, env={}, path=tmp_path / "none.toml")
    fleet = SimFleet(NAMES)
    store = Store(tmp_path / "console.db")
    gateways = {
        name: RobotGateway(
            SimBackend(sim, store, stepped_elsewhere=True),
            make_safety(settings, store),
            store=store,
            who="test",
            latch_key=f"/{name}",
        )
        for name, sim in zip(NAMES, fleet.robots, strict=True)
    }
    path = tmp_path / "fleet.mcap"
    found = NAMES[:1]
    recorder = SessionRecorder(
        path,
        gateways["astibot_1"],
        store,
        fleet=lambda: [(name, f"/{name}") for name in found],
        gateway_of=gateways.get,
    )
    sent = gateways["astibot_2"].run(goto_command("shipping"), confirm=lambda _c: True)
    assert sent.executed, sent.reason
    for i in range(40):  # 8 s of simulated time, a poll each 0.2 s
        if i == 2:
            found = NAMES  # astibot_2 joins: recorded from now
        fleet.step(0.2)
        recorder.poll()
    gateways["astibot_1"].estop()
    for _ in range(6):  # its status (2 Hz) says so
        fleet.step(0.2)
        recorder.poll()
    recorder.stop()
    ends = {name: sim.pose[:2] for name, sim in zip(NAMES, fleet.robots, strict=True)}
    return path, settings, store, ends


def test_every_robot_recorded_under_its_namespace_and_replayed_where_it_was(tmp_path):
    path, _settings, store, ends = _record(tmp_path)
    counts = summary(path)
    for name in NAMES:
        assert counts.get(f"/{name}/odom", 0) >= 30, counts
        assert counts.get(f"/{name}/robot_status", 0) >= 10, counts  # 2 Hz
    assert "/odom" not in counts, "no topic left out of its robot's namespace"
    assert counts.get("/astibot_1/astiop/events", 0) >= 1, counts  # its E-STOP, its own
    assert math.dist(ends["astibot_1"], ends["astibot_2"]) > 2.0, ends

    recording = Recording(path)
    assert fleet_of(recording) == [("astibot_1", "/astibot_1"), ("astibot_2", "/astibot_2")]
    robots = open_fleet_replay(recording, fleet_of(recording), paused=True)
    assert robots[1].playback is robots[0].playback, "one clock for the fleet"
    robots[0].playback.seek(recording.duration_s)
    for name, backend in zip(NAMES, robots, strict=True):
        st = backend.state()
        assert math.dist((st.pose.x, st.pose.y), ends[name]) < 0.3, (name, st.pose, ends)
    assert robots[0].e_stopped and not robots[1].e_stopped
    assert any("E-STOP" in ev.message for ev in robots[0].events_since(0))
    assert not any("E-STOP" in ev.message for ev in robots[1].events_since(0))
    driven = RobotGateway(robots[1]).drive(0.1, 0.0, 0.0)
    assert not driven.executed and READ_ONLY in f"{driven.reason} {driven.error}", driven
    store.close()


async def test_the_replay_of_a_fleet_session_lists_every_robot(tmp_path):
    from astiop.app import make_app

    path, settings, store, ends = _record(tmp_path)
    recording = Recording(path)
    replay_store = Store(tmp_path / "replay.db")
    current, watch = replayed_fleet(
        settings, recording, fleet_of(recording), replay_store, speed=16.0, paused=False
    )
    app = make_app(current, replay_store, gateway=watch.robots[0][2](), fleet=watch)
    async with app.run_test(size=(140, 40)) as pilot:
        await pilot.press("f7")
        table = app.screen.query_one(DataTable)
        await wait_for(pilot, lambda: table.row_count == 2 and app.fleet.rows()[1].x is not None)
        await wait_for(pilot, lambda: abs(app.fleet.rows()[1].x - ends["astibot_2"][0]) < 0.3)
        rows = [[str(c) for c in table.get_row_at(i)] for i in range(2)]
        assert [r[0] for r in rows] == ["▶ astibot_1", "  astibot_2"], rows  # ▶ the current one
        assert "astibot_1" in str(app.screen.query_one("#fleet-current").render())
    store.close()
    replay_store.close()

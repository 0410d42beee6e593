"""A recording replayed: the state it shows is the recorded one, its clock obeys the keys, and
nothing is ever sent to a robot."""

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from mcap_ros2.writer import Writer

from astiop.app import make_app
from astiop.config import load_settings
from astiop.recording.reader import Recording
from astiop.robot.gateway import RobotGateway
from astiop.store import Store
from astiop.transports.replay.backend import READ_ONLY, open_replay
from tests.cli_runner import run_cli
from tests.recordings import GOTO, record_trip
from tests.tui_helpers import ask, wait_for


@pytest.fixture(scope="module")
def trip(tmp_path_factory):
    return record_trip(tmp_path_factory.mktemp("trip"))


def independent(path, topic):
    """(log time ns, message) as mcap-ros2-support reads them."""
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        return [(m.log_time, msg) for _s, _c, m, msg in reader.iter_decoded_messages([topic])]


def test_the_replayed_pose_is_the_recorded_one_wherever_the_cursor_is(trip):
    backend = open_replay(trip, paused=True)
    poses = independent(trip, "/robot_pose")
    assert len(poses) > 100
    for t_ns, msg in poses[:: len(poses) // 7]:
        backend.playback.seek((t_ns - backend.playback.start_ns) / 1e9)
        pose = backend.state().pose
        assert (pose.x, pose.y) == pytest.approx((msg.x, msg.y), abs=1e-9)
    backend.playback.seek(1e9)  # past the end: the last message, and the clock stops there
    last = poses[-1][1]
    assert backend.state().pose.x == pytest.approx(last.x)
    assert backend.state().state_word == "idle"  # it arrived
    battery = independent(trip, "/battery_status")[-1][1]
    assert backend.state().battery.percentage == pytest.approx(battery.percentage)


OCCUPANCY_GRID = """std_msgs/Header header
nav_msgs/MapMetaData info
int8[] data
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: nav_msgs/MapMetaData
builtin_interfaces/Time map_load_time
float32 resolution
uint32 width
uint32 height
geometry_msgs/Pose origin
================================================================================
MSG: geometry_msgs/Pose
geometry_msgs/Point position
geometry_msgs/Quaternion orientation
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
"""


def slam_bag(path):
    """A robot's /map as a ros2 bag holds it: 3 x 2 cells at 0.5 m, all free at 0 s, one
    cell occupied from 2 s."""
    with open(path, "wb") as fh:
        writer = Writer(fh)
        schema = writer.register_msgdef("nav_msgs/msg/OccupancyGrid", OCCUPANCY_GRID)
        for t_s, data in ((0, [0] * 6), (2, [0, 0, 100, 0, 0, 0])):
            stamp = {"sec": t_s, "nanosec": 0}
            origin = {"position": {"x": -1.0, "y": 0.0, "z": 0.0}, "orientation": {"w": 1.0}}
            info = {"map_load_time": stamp, "resolution": 0.5, "width": 3, "height": 2}
            info["origin"] = origin
            msg = {"header": {"stamp": stamp, "frame_id": "map"}, "info": info, "data": data}
            t_ns = (1_000 + t_s) * 10**9
            writer.write_message("/map", schema, msg, log_time=t_ns, publish_time=t_ns)
        writer.finish()
    return path


def test_the_recorded_map_is_decoded_once_per_message(tmp_path):
    backend = open_replay(slam_bag(tmp_path / "slam.mcap"), paused=True)
    first = backend.map_geometry()
    assert first.bounds == (-1.0, 0.0, 0.5, 1.0) and not (first.cells >= 50).any()
    assert backend.map_geometry() is first  # the same object: the map view keeps its pixels
    backend.playback.seek(2.5)  # the robot's map grew
    second = backend.map_geometry()
    assert second is not first and (second.cells >= 50).sum() == 1
    assert backend.map_geometry() is second
    backend.playback.seek(0.5)
    assert not (backend.map_geometry().cells >= 50).any()


def test_the_clock_pauses_steps_and_changes_speed(trip):
    backend = open_replay(trip, paused=True)
    pb = backend.playback
    assert pb.position_s == 0.0 and not pb.playing
    pb.step(1)
    pb.step(1)
    assert pb.position_s == pytest.approx(2.0)
    pb.step(-5)
    assert pb.position_s == 0.0  # never before the start
    assert [pb.faster(True), pb.faster(True), pb.faster(False), pb.faster(False)] == [2, 4, 2, 1]
    for _ in range(10):
        pb.faster(False)
    assert pb.speed == 0.25
    pb.step(10_000)
    assert pb.position_s == pytest.approx(pb.duration_s) and not pb.playing
    assert pb.toggle() and pb.position_s < 1.0  # play again from the start


def test_events_and_turns_come_as_the_cursor_reaches_them(trip, tmp_path):
    store = Store(tmp_path / "replay.db")
    backend = open_replay(trip, store=store, paused=True)
    assert backend.events_since(0) == []  # the goal is accepted 0.1 s in
    backend.state()
    assert store.interactions() == []
    backend.playback.step(10)
    events = backend.events_since(0)
    assert events and "accepted" in events[0].message
    backend.state()
    turns = store.interactions()
    assert [t["prompt"] for t in turns] == ["where is it?"] and turns[0]["session"] == "replay"


def test_a_replay_refuses_every_command_and_teleop(trip, tmp_path):
    store = Store(tmp_path / "replay.db")
    gateway = RobotGateway(open_replay(trip, store=store), store=store, who="replay")
    asked = []
    for cmd in (GOTO % "shipping", "ros2 topic echo /robot_pose --once", "ros2 node list"):
        result = gateway.run(cmd, confirm=lambda c: asked.append(c) or True)
        assert not result.executed and result.reason == READ_ONLY
    assert asked == []  # refused before anyone is asked
    drive = gateway.drive(0.2, 0.0, 0.0)
    assert not drive.executed and drive.reason == READ_ONLY


def test_a_recording_cut_off_mid_way_replays_up_to_the_cut(trip, tmp_path):
    data = trip.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) * 2 // 3])
    whole, part = Recording(trip), Recording(cut)
    assert part.cut and not whole.cut
    assert 0 < part.counts()["/robot_pose"] < whole.counts()["/robot_pose"]
    backend = open_replay(cut)
    assert "cut off" in backend.events_since(0)[0].message


def test_replay_refuses_bad_input_in_one_line(tmp_path):
    notes = tmp_path / "notes.txt"
    notes.write_text("not a recording\n")
    for args, says in (
        (("replay", str(tmp_path / "none.mcap")), "no such recording"),
        (("replay", str(notes)), "not an MCAP recording"),
        (("replay", "--speed", "100", str(notes)), "--speed"),
    ):
        out = run_cli("--db", str(tmp_path / "r.db"), *args)
        assert out.returncode == 2 and says in out.stderr, out.stderr
        assert len(out.stderr.strip().splitlines()) == 1


@pytest.mark.slow
async def test_the_replay_console_shows_the_recording_and_refuses_commands(trip, tmp_path):
    settings = load_settings({"llm": {"model": "rules"}}, env={}, path=tmp_path / "none.toml")
    store = Store(tmp_path / "replay.db")
    gateway = RobotGateway(open_replay(trip, store=store, paused=True), store=store)
    app = make_app(settings, store, gateway=gateway, sample_hz=20)
    async with app.run_test(size=(120, 40)) as pilot:
        bar = app.screen.query_one("#replay-bar")
        await wait_for(pilot, lambda: "⏸" in str(bar.render()) and "00:00.0" in str(bar.render()))
        assert "replay of trip.mcap" in app.sub_title
        await pilot.press("right", "right", "right")
        await wait_for(pilot, lambda: "00:03.0" in str(bar.render()))
        cursor_s = gateway.playback.now_ns() / 1e9  # paused there: the sampler catches up
        await wait_for(pilot, lambda: abs(app.robot_state.t - cursor_s) < 1e-3)
        x_at_3 = app.robot_state.pose.x
        await pilot.press("shift+right")
        # the recorded robot moved on
        await wait_for(pilot, lambda: app.robot_state.pose.x > x_at_3 + 1.0)
        await pilot.press("right_square_bracket", "space")
        assert gateway.playback.playing and gateway.playback.speed == 2.0
        await wait_for(pilot, lambda: "▶ 2×" in str(bar.render()))
        text = await ask(app, pilot, "send the robot to shipping")
        assert "replay is read-only" in text
        assert app.screen.query_one("#replay-bar") is not None
    assert store.commands_for(store.interactions()[0]["id"])[0]["executed"] == 0

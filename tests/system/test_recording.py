"""Sessions as MCAP, read back with mcap-ros2-support's own reader (not astiop's code)."""

import json
import math
import os
import signal
import subprocess
import sys
import time

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from astiop.recording import summary
from astiop.ros2.catalog import astibot_catalog
from tests.cli_runner import run_cli

ROS_TOPICS = astibot_catalog().recorded_topics()


def decoded(path, topics=ROS_TOPICS):
    """(topic, message) as mcap-ros2-support's decoder reads them."""
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _schema, channel, _message, msg in reader.iter_decoded_messages(topics=list(topics)):
            yield channel.topic, msg


def test_a_recorded_trip_decodes_with_the_ros2_reader(tmp_path, monkeypatch):
    monkeypatch.setenv("ASTIOP_SIM__SPEED", "10")
    path = tmp_path / "trip.mcap"
    out = run_cli(
        "--db",
        str(tmp_path / "r.db"),
        "record",
        "--goto",
        "inspection_zone_a",
        "--scan-hz",
        "5",
        "--json",
        str(path),
    )
    assert out.returncode == 0, out.stderr
    counts = json.loads(out.stdout)["messages"]
    for topic in (
        "/robot_pose",
        "/odom",
        "/battery_status",
        "/robot_status",
        "/scan",
        "/obstacles",
        "/plan",
        "/tf",
        "/diagnostics",
        "/conveyor/status",
    ):
        assert counts.get(topic, 0) > 0, topic
    assert summary(path) == counts  # the file's own summary lists each topic's count
    poses, scans, batteries = [], [], []
    for topic, msg in decoded(path):
        if topic == "/robot_pose":
            poses.append((msg.x, msg.y))
        elif topic == "/scan":
            scans.append(len(msg.ranges))
        elif topic == "/battery_status":
            batteries.append(msg.percentage)
            assert msg.power_supply_technology == 8  # VRLA, on Jazzy
    assert math.dist(poses[-1], (15.0, 3.5)) < 0.3 and math.dist(poses[0], (15.0, 3.5)) > 5
    assert set(scans) == {360}
    assert all(0.0 < b <= 1.0 for b in batteries)
    with path.open("rb") as fh:  # the JSON channels carry their JSON schema
        reader = make_reader(fh)
        info = reader.get_summary()
        events = [c for c in info.channels.values() if c.topic == "/astiop/events"]
        assert events and events[0].message_encoding == "json"
        assert info.schemas[events[0].schema_id].encoding == "jsonschema"


@pytest.mark.slow
def test_a_recording_killed_mid_way_keeps_its_chunks_and_repairs(tmp_path):
    path = tmp_path / "cut.mcap"
    env = {**os.environ, "ASTIOP_SIM__SPEED": "5"}
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "astiop",
            "--db",
            str(tmp_path / "k.db"),
            "record",
            "--duration",
            "60",
            str(path),
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and (not path.exists() or path.stat().st_size < 20_000):
        time.sleep(0.2)  # a flush every 2 s: wait for a few chunks
    time.sleep(2.5)
    proc.send_signal(signal.SIGKILL)
    proc.wait(10)
    out = run_cli("record", "--repair", "--json", str(path))
    assert out.returncode == 0, out.stderr
    recovered = json.loads(out.stdout)["messages"]
    assert recovered.get("/robot_pose", 0) > 10 and recovered.get("/battery_status", 0) > 0
    fixed = tmp_path / "cut.repaired.mcap"
    assert summary(fixed) == recovered
    assert sum(1 for _ in decoded(fixed, ["/scan"])) > 0


def test_record_refuses_bad_input_in_one_line(tmp_path):
    db = str(tmp_path / "b.db")
    for args in (
        ("record", "--goto", "nowhere"),
        ("record", "--duration", "nan"),
        ("record", "--repair", str(tmp_path / "none.mcap")),
    ):
        out = run_cli("--db", db, *args)
        assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1, out.stderr


def _sim_recording(tmp_path):
    """A store, and a paused simulator behind a real gateway (stepped by the test)."""
    from astiop.config import load_settings
    from astiop.robot.factory import make_sim_gateway
    from astiop.sim.simulator import Simulator
    from astiop.store import Store

    store = Store(tmp_path / "rec.db")
    sim = Simulator(seed=0)
    settings = load_settings({}, env={}, path=tmp_path / "none.toml")
    return store, sim, make_sim_gateway(settings, store, sim=sim)


def _json_messages(path, topic):
    """(log time in s, the JSON) of each message on a JSON channel, read with mcap's reader."""
    with open(path, "rb") as fh:
        return [
            (message.log_time / 1e9, json.loads(message.data))
            for _s, _c, message in make_reader(fh).iter_messages(topics=[topic])
        ]


class _LinkThatDrops:
    """The robot's gateway, whose reads fail while `dropped` is set, as a lost link's would."""

    def __init__(self, gateway):
        import threading

        self._gateway = gateway
        self.dropped = threading.Event()
        self.failed = 0

    def messages(self, names):
        from astiop.transports.base import BackendError

        if self.dropped.is_set():
            self.failed += 1
            raise BackendError("the robot link dropped")
        return self._gateway.messages(names)

    def __getattr__(self, name):
        return getattr(self._gateway, name)


def _until(condition, what, timeout_s=60.0):
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def test_a_recording_goes_on_after_failed_polls_says_so_once_and_finishes(tmp_path, capfd):
    from astiop.recording import SessionRecorder

    store, sim, gateway = _sim_recording(tmp_path)
    link = _LinkThatDrops(gateway)
    said = []
    path = tmp_path / "dropped.mcap"
    recorder = SessionRecorder(path, link, store, flush_s=0.0, on_error=said.append).start()
    sim.step(0.5)
    _until(lambda: recorder.counts.get("/robot_pose", 0) >= 1, "a first pose")
    link.dropped.set()
    _until(lambda: link.failed >= 5, "five failed polls")
    link.dropped.clear()
    back_at = sim.t
    sim.step(1.0)  # the robot's clock moves on: new messages to record
    turn = store.start_interaction(model="rules", mode="rules", prompt="where is it?")
    store.update_interaction(turn, status="done", answer="x 5.0, y 3.5")
    _until(lambda: recorder.counts.get("/astiop/interactions", 0) == 1, "the turn")
    _until(lambda: recorder.counts.get("/robot_pose", 0) >= 2, "a pose after the drop")
    link.dropped.set()  # and dropped again as the recording stops: the file is finished anyway
    _until(lambda: link.failed >= 8, "more failed polls")
    counts = recorder.stop()
    assert not recorder._thread.is_alive()

    assert summary(path) == counts  # a finished file: its summary is there
    poses = [msg for topic, msg in decoded(path, ["/robot_pose"])]
    assert len(poses) == counts["/robot_pose"] >= 2
    with open(path, "rb") as fh:
        pose_times = [
            m.log_time / 1e9 for _s, _c, m in make_reader(fh).iter_messages(["/robot_pose"])
        ]
    assert max(pose_times) > back_at  # recorded after the polls that failed
    assert [turn["prompt"] for _t, turn in _json_messages(path, "/astiop/interactions")] == [
        "where is it?"
    ]
    assert len(said) == 1 and "the robot link dropped" in said[0]  # said once, not per poll
    err = capfd.readouterr().err
    assert [line for line in err.splitlines() if "the robot link dropped" in line] == [
        f"astiop: {said[0]}"
    ]
    assert recorder.failures >= 8
    gateway.close()
    store.close()


def test_every_turn_reaches_the_recording_once_whatever_order_turns_end_in(tmp_path):
    from astiop.recording import SessionRecorder
    from astiop.store import Store

    store, sim, gateway = _sim_recording(tmp_path)
    mcp = Store(tmp_path / "rec.db")  # another process's turns, on its own connection
    before = store.start_interaction(model="rules", mode="rules", prompt="done before")
    store.update_interaction(before, status="done")
    across = store.start_interaction(model="rules", mode="rules", prompt="running at the start")
    path = tmp_path / "turns.mcap"
    recorder = SessionRecorder(path, gateway, store, flush_s=0.0)

    chat = store.start_interaction(model="rules", mode="rules", prompt="chat turn")
    call = mcp.start_interaction(model="mcp", mode="mcp", prompt="mcp call")
    mcp.update_interaction(call, status="done")  # ends first, though it started second
    sim.step(0.1)
    recorder.poll()
    store.update_interaction(chat, status="done")
    sim.step(0.1)
    recorder.poll()
    recorder.poll()
    store.update_interaction(across, status="error", error="the model server went away")
    recorder.stop()

    written = [turn["prompt"] for _t, turn in _json_messages(path, "/astiop/interactions")]
    assert written == ["mcp call", "chat turn", "running at the start"]  # as they ended, once
    gateway.close()
    mcp.close()
    store.close()


def test_the_alerts_any_process_fires_reach_the_recording_once(tmp_path):
    """An alert fired before the recording is not in it; one another process writes during it
    is, once, on /astiop/alerts, with its reading and the watch that fired it."""
    from astiop.recording import SessionRecorder
    from astiop.recording.alerts import POLL_S
    from astiop.store import Store

    store, sim, gateway = _sim_recording(tmp_path)
    watcher = Store(tmp_path / "rec.db")  # `astiop watch run`, on its own connection
    watcher.fire_alert("astibot/battery_low", robot="", kind="battery_low", message="before")
    path = tmp_path / "alerts.mcap"
    recorder = SessionRecorder(path, gateway, store, flush_s=0.0)
    fired = watcher.fire_alert(
        "/watch:3", robot="", kind="watch", message="the battery is below 90 %: 85.00 %",
        reading="85.00 %", reading_age_s=0.1, watch_id=3,
    )  # fmt: skip
    for _ in range(3):
        sim.step(0.1)
        recorder.poll()
        time.sleep(POLL_S)
    recorder.stop()
    written = [alert for _t, alert in _json_messages(path, "/astiop/alerts")]
    assert [(a["id"], a["kind"], a["reading"], a["watch_id"]) for a in written] == [
        (fired, "watch", "85.00 %", 3)
    ]
    assert written[0]["message"] == "the battery is below 90 %: 85.00 %"
    gateway.close()
    watcher.close()
    store.close()

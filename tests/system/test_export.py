"""A stretch of time exported from the store and the recordings, read back independently."""

import json
import time
from datetime import datetime, timezone

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from astiop.recording.export import ExportError, parse_time
from astiop.recording.reader import Recording
from tests.cli_runner import run_cli
from tests.recordings import record_trip


@pytest.fixture(scope="module")
def kept(tmp_path_factory):
    """A data dir as astiop keeps it: rec.db and sessions/trip.mcap."""
    folder = tmp_path_factory.mktemp("kept")
    (folder / "sessions").mkdir()
    trip = record_trip(folder)
    trip.rename(folder / "sessions" / "trip.mcap")
    return folder


def test_times_are_read_in_every_documented_form():
    now = 1_795_000_000.0
    assert parse_time("now", now) == now
    assert parse_time("-10m", now) == now - 600
    assert parse_time("-1.5h", now) == now - 5400
    assert parse_time("1795000123", now) == 1795000123
    utc = datetime(2026, 11, 22, 14, 5, tzinfo=timezone.utc).timestamp()
    assert parse_time("2026-11-22T14:05+00:00", now) == utc
    local = datetime.fromtimestamp(now).replace(hour=9, minute=30, second=0, microsecond=0)
    assert parse_time("09:30", now) == local.timestamp()
    for bad in ("yesterday", "-10x", "25:99", ""):
        with pytest.raises(ExportError):
            parse_time(bad, now)


def _window(kept, lead_s=None):
    rec = Recording(kept / "sessions" / "trip.mcap")
    t0 = rec.start_ns / 1e9 + rec.wall_offset_s()
    t1 = (t0 + lead_s) if lead_s is not None else rec.end_ns / 1e9 + rec.wall_offset_s() + 60
    return rec, t0 - 60, t1


def test_an_mcap_export_holds_the_robot_and_the_store_in_wall_time(kept):
    rec, t0, t1 = _window(kept)
    out = kept / "all.mcap"
    args = ["--db", str(kept / "rec.db"), "export", "session", "--json", "-o", str(out)]
    res = run_cli(*args, "--from", repr(t0), "--to", repr(t1))
    assert res.returncode == 0, res.stderr
    report = json.loads(res.stdout)
    assert report["recordings"] == [str(kept / "sessions" / "trip.mcap")]
    with open(out, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        poses = [
            (m.log_time, msg) for _s, _c, m, msg in reader.iter_decoded_messages(["/robot_pose"])
        ]
    assert len(poses) == rec.counts()["/robot_pose"] == report["messages"]["/robot_pose"]
    assert all(t0 * 1e9 <= t <= t1 * 1e9 for t, _ in poses)  # wall clock, not sim time
    last = rec.latest(["/robot_pose"], rec.end_ns)["/robot_pose"]
    assert (poses[-1][1].x, poses[-1][1].y) == (last["x"], last["y"])
    with open(out, "rb") as fh:
        turns = [
            json.loads(m.data)
            for _s, c, m in make_reader(fh).iter_messages()
            if c.topic == "/astiop/interactions"
        ]
    assert [t["prompt"] for t in turns] == ["where is it?"]


def test_a_window_keeps_only_what_falls_in_it(kept):
    rec, t0, t1 = _window(kept, lead_s=5.0)
    out = kept / "first.jsonl"
    args = ["--db", str(kept / "rec.db"), "export", "session", "--format", "jsonl"]
    res = run_cli(*args, "-o", str(out), "--from", repr(t0), "--to", repr(t1))
    assert res.returncode == 0, res.stderr
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    times = [line["t"] for line in lines]
    assert times == sorted(times) and all(t0 <= t <= t1 for t in times)
    poses = [line for line in lines if line["topic"] == "/robot_pose"]
    start = rec.start_ns / 1e9 + rec.wall_offset_s()
    expected = sum(1 for t in rec.channels["/robot_pose"].times if t / 1e9 <= 5.0 + 1e-9)
    assert len(poses) == expected and 0 < expected < rec.counts()["/robot_pose"]
    assert poses[0]["data"].keys() == {"x", "y", "theta"}
    assert all(p["t"] <= start + 5.0 + 1e-6 for p in poses)


def test_export_refuses_bad_input_in_one_line(tmp_path):
    db = ["--db", str(tmp_path / "e.db"), "export", "session"]
    for args, says in (
        (["--from", "yesterday"], "cannot read the time"),
        (["--from", "now", "--to", "-1h"], "is before"),
        (["--format", "csv"], "mcap or jsonl"),
        (["--recordings", str(tmp_path / "none")], "no such folder"),
    ):
        res = run_cli(*db, *args)
        assert res.returncode == 2 and says in res.stderr, res.stderr
        assert len(res.stderr.strip().splitlines()) == 1
    empty = run_cli(*db, "--from", str(int(time.time()) - 5), "-o", str(tmp_path / "e.jsonl"))
    assert empty.returncode == 0 and "0 records" in empty.stdout
    assert (tmp_path / "e.jsonl").read_text() == ""  # the suffix chose the format

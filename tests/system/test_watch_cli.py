"""`astiop watch` and `astiop alerts` on the simulator: a battery watch fires once when the
simulated battery crosses its threshold, and two `watch run` processes on one database write
each alert once."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

from astiop.store import Store
from tests.cli_runner import run_cli

# docked at the start, the simulated robot charges: 20.3 % crosses 21 % a few seconds in
SIM = {"ASTIOP_SIM__BATTERY": "0.203", "ASTIOP_SIM__SPEED": "100", "ASTIOP_SIM__SEED": "0"}


def _watch_run(db) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "astiop", "--db", str(db), "watch", "run", "--json"],
        env={**os.environ, **SIM},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_for_alerts(db, watch_id: int, timeout_s: float = 90.0) -> None:
    store = Store(db)
    try:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if any(a["watch_id"] == watch_id for a in store.list_alerts()):
                return
            time.sleep(0.1)
        raise AssertionError(f"watch {watch_id} never fired")
    finally:
        store.close()


def _stop(proc: subprocess.Popen) -> str:
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    return out


def test_a_battery_watch_fires_once_when_the_simulated_battery_crosses_it(tmp_path):
    db = tmp_path / "w.db"
    added = run_cli("--db", str(db), "watch", "add", "tell me when the battery is above 21 %")
    assert added.returncode == 0, added.stderr
    assert added.stdout.strip() == "watch 1: I will tell you when the battery is above 21 % (once)"
    marker = run_cli("--db", str(db), "watch", "add", "--field", "battery", "--above", "21.5")
    assert marker.returncode == 0, marker.stderr
    follower = subprocess.Popen(
        [sys.executable, "-m", "astiop", "--db", str(db), "alerts", "--follow", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    proc = _watch_run(db)
    try:
        _wait_for_alerts(db, 2)  # the battery went on past 21.5 %: watch 1 had its chance again
    finally:
        printed = _stop(proc)
    followed = []  # `alerts --follow` in another process prints each as it is written
    for line in follower.stdout:
        followed.append(json.loads(line))
        if len(followed) == 2:
            break
    follower.send_signal(signal.SIGINT)
    follower.communicate(timeout=30)
    assert follower.returncode == 0
    assert [a["watch_id"] for a in followed] == [1, 2]
    lines = [json.loads(line) for line in printed.splitlines()]
    assert [(a["kind"], a["watch_id"]) for a in lines] == [("watch", 1), ("watch", 2)]
    alerts = json.loads(run_cli("--db", str(db), "alerts", "--json").stdout)
    assert [a["watch_id"] for a in alerts] == [1, 2]
    first = alerts[0]
    assert first["message"].startswith("the battery is above 21 %: 21.")
    assert 21.0 <= float(first["reading"].removesuffix(" %")) < 21.5
    assert first["reading_age_s"] is not None and first["reading_age_s"] >= 0
    listed = json.loads(run_cli("--db", str(db), "watch", "list", "--json").stdout)
    assert [w["armed"] for w in listed] == [False, False]  # once: fired, disarmed


def test_two_watch_run_processes_on_one_database_write_each_alert_once(tmp_path):
    db = tmp_path / "w.db"
    assert (
        run_cli(
            "--db", str(db), "watch", "add", "alert me if the battery rises above 21 percent"
        ).returncode
        == 0
    )
    first, second = _watch_run(db), _watch_run(db)
    try:
        _wait_for_alerts(db, 1)
    finally:
        out1, out2 = _stop(first), _stop(second)
    alerts = json.loads(run_cli("--db", str(db), "alerts", "--json").stdout)
    assert [a["watch_id"] for a in alerts] == [1]
    assert len(out1.splitlines()) + len(out2.splitlines()) == 1  # printed by the one that wrote it


def test_a_watch_that_cannot_be_kept_is_one_line_and_nothing_is_stored(tmp_path):
    db = str(tmp_path / "w.db")
    out = run_cli("--db", db, "watch", "add", "tell me when the battery is below 20 metres")
    assert out.returncode == 2
    assert out.stderr == "astiop: the battery is measured in %, not 'metres'; nothing was stored\n"
    out = run_cli("--db", db, "watch", "add", "what is the battery level")
    assert out.returncode == 2 and "is no watch astiop understands" in out.stderr
    assert json.loads(run_cli("--db", db, "watch", "list", "--json").stdout) == []
    assert (
        run_cli("--db", db, "watch", "remove", "7").stderr
        == "astiop: no watch 7 (astiop watch list)\n"
    )

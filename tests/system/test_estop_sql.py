"""The shared E-STOP latch: `astiop estop` writes it before loading anything else, in the
database the settings name; and a process that followed another's E-STOP follows its release
with no screen asking for the state."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path

from astiop import estop_sql
from astiop.config import load_settings
from astiop.robot.factory import make_sim_gateway
from astiop.sim.simulator import Simulator
from astiop.store import Store
from tests.ros import until

PUBLISH = "ros2 topic pub -t 300 -r 10 /cmd_vel geometry_msgs/msg/Twist '{linear: {x: -0.2}}'"


def test_the_early_latch_reads_the_database_the_settings_read(tmp_path, monkeypatch):
    config = tmp_path / "config.toml"
    config.write_text(f'db = "{tmp_path / "from-file.db"}"\n')
    env = {"ASTIOP_CONFIG": str(config)}
    assert estop_sql.db_path(["--db", "a.db", "estop"], env) == Path("a.db")
    assert estop_sql.db_path(["--db=b.db", "estop"], env) == Path("b.db")
    assert estop_sql.db_path(["estop"], {**env, "astiop_db": "c.db"}) == Path("c.db")  # any case
    assert estop_sql.db_path(["estop"], env) == tmp_path / "from-file.db"
    for args, want in [(["--db", "a.db"], "a.db"), ([], str(tmp_path / "from-file.db"))]:
        settings = load_settings({"db": args[1]} if args else {}, env={}, path=config)
        assert str(settings.db) == want
    assert estop_sql.db_path(["estop"], {"ASTIOP_CONFIG": str(tmp_path / "none.toml")}).name == (
        "astiop.db"
    )


def test_the_early_latch_latches_with_nothing_heavy_imported(tmp_path):
    db = tmp_path / "e.db"
    Store(db).close()
    code = (
        "import json, sys; from astiop import estop_sql; "
        f"ok = estop_sql.latch_early(['--db', {str(db)!r}, 'estop']); "
        "print(json.dumps([ok, sorted(m for m in sys.modules "
        "if m.startswith(('astiop.store', 'astiop.robot', 'sqlite_utils', 'numpy')))]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    ok, heavy = json.loads(out.stdout)
    assert ok and heavy == []
    store = Store(db)
    assert store.estop_latch()["by"] == "estop"
    store.close()


def test_the_early_latch_never_gets_in_the_way(tmp_path):
    assert not estop_sql.latch_early(["--db", str(tmp_path / "none.db"), "estop"])  # no file yet
    assert not estop_sql.latch_early(["--db", str(tmp_path), "estop"])  # a folder
    (tmp_path / "junk.db").write_text("not sqlite")
    assert not estop_sql.latch_early(["--db", str(tmp_path / "junk.db"), "estop"])


def test_a_process_that_followed_an_estop_follows_its_release_unasked(tmp_path):
    """Two processes' gateways on one database: the first's timed publish is ended by the
    second's E-STOP, and its robot moves again once the second releases, with no one calling
    state() in the first."""
    settings = load_settings({}, env={}, path=tmp_path / "none.toml")
    mine, theirs = Store(tmp_path / "shared.db"), Store(tmp_path / "shared.db")
    gateway = make_sim_gateway(settings, mine, realtime=True, sim=Simulator(seed=1))
    other = make_sim_gateway(settings, theirs, realtime=True, sim=Simulator(seed=2))
    gateway.start()
    try:
        results = []
        run = threading.Thread(target=lambda: results.append(gateway.run(PUBLISH, lambda _c: True)))
        run.start()
        assert until(lambda: gateway.backend.inflight.busy, 10)
        other.estop()
        run.join(10)
        assert not run.is_alive(), "the publish outlived another process's E-STOP"
        assert "E-STOP ended it" in results[0].error, results[0]
        assert gateway.backend.e_stopped
        other.release_estop()
        assert until(lambda: not gateway.backend.e_stopped, 5), "the release was not followed"
    finally:
        gateway.close()
        other.close()
        mine.close()
        theirs.close()

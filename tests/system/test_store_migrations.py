"""Schema migrations are atomic: a process killed inside one, or several processes opening one new
file at once, never leave a database that cannot be opened."""

import json
import sqlite3
import subprocess
import sys

import pytest

from astiop.store import SCHEMA_VERSION, Store

# A process that opens the store and dies (os._exit: no clean-up, no rollback of its own) as the
# Nth SQL statement of any of its connections starts; with N = 0 it lists the statements.
KILLED_AT = r"""
import json, os, sqlite3, sys

path, stop_at = sys.argv[1], int(sys.argv[2])
seen = []
_connect = sqlite3.connect


def connect(*args, **kwargs):
    conn = _connect(*args, **kwargs)

    def trace(statement):
        seen.append(statement)
        if len(seen) == stop_at:
            os._exit(9)

    conn.set_trace_callback(trace)
    return conn


sqlite3.connect = connect
from astiop.store import Store

Store(path).close()
print(json.dumps(seen))
"""

# A process that opens the store when told to ("go" on stdin), after saying it is ready.
OPENER = r"""
import sys
from astiop.store import Store

print("ready", flush=True)
sys.stdin.readline()
store = Store(sys.argv[1])
print(len(store.list_locations()), store.schema_version(), flush=True)
store.close()
"""


def _schema(path) -> tuple[int, list]:
    """(user_version, every table, index and its SQL), read with plain sqlite3."""
    conn = sqlite3.connect(path)
    try:
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        rows = conn.execute("SELECT type, name, sql FROM sqlite_master ORDER BY name").fetchall()
    finally:
        conn.close()
    return version, rows


def _killed_at(path, n: int) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", KILLED_AT, str(path), str(n)],
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.mark.slow
def test_a_process_killed_at_any_statement_of_any_migration_leaves_a_database_that_opens(tmp_path):
    clean = Store(tmp_path / "clean.db")
    seeded = sorted(loc.name for loc in clean.list_locations())
    clean.close()
    _, clean_schema = _schema(tmp_path / "clean.db")

    listed = _killed_at(tmp_path / "count.db", 0)
    assert listed.returncode == 0, listed.stderr
    statements = json.loads(listed.stdout)
    assert len(statements) > 20  # every migration's statements are among them

    schemas: dict[int, set[str]] = {}  # version -> the schemas seen at it after a kill
    for n in range(1, len(statements) + 1):
        path = tmp_path / f"killed-{n}.db"
        out = _killed_at(path, n)
        assert out.returncode == 9, (n, statements[n - 1], out.stderr)
        if path.exists():
            version, rows = _schema(path)
            schemas.setdefault(version, set()).add(json.dumps(rows))
        store = Store(path)  # the next open finishes what the killed one began
        try:
            assert store.schema_version() == SCHEMA_VERSION, statements[n - 1]
            assert sorted(loc.name for loc in store.list_locations()) == seeded  # seeded once
            store.add_location("dock_two", 3.0, 4.0)
            turn = store.start_interaction(model="rules", mode="rules", prompt="where?")
            store.update_interaction(turn, status="done", answer="here")
            store.add_command(turn, command="ros2 topic list", valid=1, provenance="measured")
            store.latch_estop("test")
            assert store.estop_latch()["by"] == "test"
        finally:
            store.close()
        assert _schema(path) == (SCHEMA_VERSION, clean_schema), statements[n - 1]
    # A kill leaves the version before the migration it hit, whole: one schema per version,
    # and the kills reached every migration.
    assert set(range(SCHEMA_VERSION)) <= schemas.keys()
    assert {v: len(s) for v, s in schemas.items()} == {v: 1 for v in schemas}


@pytest.mark.slow
def test_eight_processes_opening_one_new_database_at_once_all_succeed(tmp_path):
    clean = Store(tmp_path / "clean.db")
    seeded = len(clean.list_locations())
    clean.close()
    failures = []
    for round_ in range(5):
        path = tmp_path / f"new-{round_}.db"
        procs = [
            subprocess.Popen(
                [sys.executable, "-c", OPENER, str(path)],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
            for _ in range(8)
        ]
        for proc in procs:  # each has imported the store: the opens start together
            assert proc.stdout.readline().strip() == "ready"
        for proc in procs:
            proc.stdin.write("go\n")
            proc.stdin.flush()
        for proc in procs:
            out, err = proc.communicate(timeout=60)
            if proc.returncode != 0 or out.split() != [str(seeded), str(SCHEMA_VERSION)]:
                failures.append((round_, out, err.strip().splitlines()[-1:]))
        store = Store(path)
        assert len(store.list_locations()) == seeded and store.schema_version() == SCHEMA_VERSION
        store.close()
    assert failures == []


def test_places_saved_before_maps_existed_are_the_warehouses(tmp_path):
    from astiop.store.schema import MIGRATIONS

    path = tmp_path / "v8.db"
    conn = sqlite3.connect(path)
    with conn:
        for migrate in MIGRATIONS[:8]:
            migrate(conn)
        conn.execute(
            "INSERT INTO locations (name, x, y, theta, description, created_at, updated_at) "
            "VALUES ('bay_7', 12.0, 9.5, 0, 'mine', 0, 0)"
        )
        conn.execute("PRAGMA user_version = 8")
    conn.close()
    store = Store(path)
    assert store.schema_version() == SCHEMA_VERSION
    assert store.get_location("bay_7").description == "mine"  # on the warehouse map
    store.use_map("turtlebot3_burger", None)
    assert store.get_location("bay_7") is None
    store.add_location("bay_7", 1.0, 1.0)  # the same name on another map
    store.close()

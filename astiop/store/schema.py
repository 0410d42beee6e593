"""The database's schema: its migrations, counted by PRAGMA user_version, and the file checks."""

from __future__ import annotations

import math
import sqlite3
import time
from pathlib import Path

import yaml

from astiop.resources import data_path
from astiop.store.records import StoreError
from astiop.store.schema_watches import _migrate_v13, _migrate_v14, _migrate_v15

SQLITE_HEADER = b"SQLite format 3\x00"


def _statements(script: str) -> list[str]:
    """A script's SQL statements one by one: executescript would COMMIT before it runs them,
    and a migration must stay inside its own transaction."""
    found, pending = [], ""
    for line in script.splitlines(keepends=True):
        pending += line
        if sqlite3.complete_statement(pending):
            found.append(pending.strip())
            pending = ""
    if pending.strip():
        raise ValueError(f"an unfinished SQL statement: {pending.strip()[:60]}")
    return found


def _run(conn: sqlite3.Connection, script: str) -> None:
    for statement in _statements(script):
        conn.execute(statement)


def _seed_locations(conn: sqlite3.Connection) -> None:
    seeds = yaml.safe_load(data_path("locations.yaml").read_text(encoding="utf-8"))
    now = time.time()
    conn.executemany(
        "INSERT INTO locations (name, x, y, theta, description, created_at, updated_at) "
        "VALUES (?, ?, ?, ?, ?, ?, ?)",
        [
            (
                s["name"],
                float(s["x"]),
                float(s["y"]),
                math.radians(float(s.get("theta_deg", 0.0))),
                s.get("description", ""),
                now,
                now,
            )
            for s in seeds
        ],
    )


_SCHEMA_V1 = """
CREATE TABLE locations (
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE COLLATE NOCASE,
    x REAL NOT NULL, y REAL NOT NULL, theta REAL NOT NULL DEFAULT 0,
    description TEXT NOT NULL DEFAULT '',
    created_at REAL NOT NULL, updated_at REAL NOT NULL
);
CREATE TABLE interactions (
    id INTEGER PRIMARY KEY,
    session TEXT, started_at REAL NOT NULL, finished_at REAL,
    model TEXT NOT NULL, mode TEXT NOT NULL, prompt TEXT NOT NULL,
    raw_replies TEXT NOT NULL DEFAULT '[]', answer TEXT,
    ttft_s REAL, total_s REAL, llm_s REAL,
    prompt_tokens INTEGER, completion_tokens INTEGER,
    status TEXT NOT NULL DEFAULT 'running', error TEXT
);
CREATE TABLE commands (
    id INTEGER PRIMARY KEY,
    interaction_id INTEGER REFERENCES interactions(id),
    seq INTEGER NOT NULL DEFAULT 0, created_at REAL NOT NULL,
    command TEXT NOT NULL, valid INTEGER NOT NULL, reason TEXT,
    kind TEXT, executed INTEGER NOT NULL DEFAULT 0,
    output TEXT, "values" TEXT
);
CREATE INDEX commands_interaction ON commands(interaction_id);
CREATE TABLE events (
    id INTEGER PRIMARY KEY,
    t REAL NOT NULL, sim_t REAL, kind TEXT NOT NULL,
    severity TEXT NOT NULL DEFAULT 'info', message TEXT NOT NULL
);
CREATE TABLE bench_runs (
    id INTEGER PRIMARY KEY,
    started_at REAL NOT NULL, finished_at REAL,
    stage INTEGER NOT NULL, models TEXT NOT NULL, modes TEXT NOT NULL,
    seed INTEGER NOT NULL DEFAULT 0, case_limit INTEGER,
    status TEXT NOT NULL DEFAULT 'running', config TEXT NOT NULL DEFAULT '{}'
);
CREATE TABLE bench_results (
    id INTEGER PRIMARY KEY,
    run_id INTEGER NOT NULL REFERENCES bench_runs(id),
    model TEXT NOT NULL, mode TEXT NOT NULL, case_id TEXT NOT NULL,
    level TEXT, category TEXT, outcome TEXT NOT NULL,
    metrics TEXT NOT NULL DEFAULT '{}', response TEXT, created_at REAL NOT NULL,
    UNIQUE (run_id, model, mode, case_id)
);
"""


def _migrate_v1(conn: sqlite3.Connection) -> None:
    _run(conn, _SCHEMA_V1)
    _seed_locations(conn)


def _migrate_v2(conn: sqlite3.Connection) -> None:
    # The E-STOP latch: one row, read by every astiop process on this database.
    _run(
        conn,
        """
        CREATE TABLE estop (
            id INTEGER PRIMARY KEY CHECK (id = 1),
            engaged INTEGER NOT NULL DEFAULT 0,
            engaged_by TEXT, engaged_at REAL, released_by TEXT, released_at REAL
        );
        INSERT INTO estop (id, engaged) VALUES (1, 0);
        """,
    )


def _migrate_v3(conn: sqlite3.Connection) -> None:
    # Grounded answers: the model's own text and why it was replaced; how a started goal ended.
    _run(
        conn,
        """
        ALTER TABLE interactions ADD COLUMN model_answer TEXT;
        ALTER TABLE interactions ADD COLUMN grounding TEXT;
        ALTER TABLE interactions ADD COLUMN outcome TEXT;
        ALTER TABLE interactions ADD COLUMN outcome_at REAL;
        """,
    )


def _migrate_v4(conn: sqlite3.Connection) -> None:
    # Every command astiop runs, with where it came from; the process behind a running turn.
    _run(
        conn,
        """
        ALTER TABLE commands ADD COLUMN source TEXT;
        ALTER TABLE interactions ADD COLUMN pid INTEGER;
        """,
    )


def _migrate_v5(conn: sqlite3.Connection) -> None:
    # An outside agent's actuation waits for a person in an open console (astiop mcp); the
    # consoles say they are open by a heartbeat.
    _run(
        conn,
        """
        CREATE TABLE approvals (
            id INTEGER PRIMARY KEY,
            client TEXT NOT NULL, command TEXT NOT NULL, detail TEXT NOT NULL DEFAULT '',
            requested_at REAL NOT NULL, expires_at REAL NOT NULL,
            status TEXT NOT NULL DEFAULT 'pending', decided_at REAL, decided_by TEXT
        );
        CREATE TABLE consoles (
            pid INTEGER PRIMARY KEY, started_at REAL NOT NULL, seen_at REAL NOT NULL
        );
        """,
    )


def _migrate_v6(conn: sqlite3.Connection) -> None:
    # What kind of fact each result is (measured, accepted, commanded, reported) and how old a
    # reading was by its stamp.
    _run(
        conn,
        """
        ALTER TABLE commands ADD COLUMN provenance TEXT;
        ALTER TABLE commands ADD COLUMN age_s REAL;
        """,
    )


def _migrate_v7(conn: sqlite3.Connection) -> None:
    # Missions: steps run one after the other, each with what the robot reported at its end.
    _run(
        conn,
        """
        CREATE TABLE missions (
            id INTEGER PRIMARY KEY,
            robot TEXT NOT NULL, request TEXT NOT NULL DEFAULT '', source TEXT NOT NULL DEFAULT '',
            status TEXT NOT NULL DEFAULT 'running', step INTEGER NOT NULL DEFAULT 0,
            reason TEXT, pid INTEGER, cancel_requested INTEGER NOT NULL DEFAULT 0,
            created_at REAL NOT NULL, finished_at REAL
        );
        CREATE TABLE mission_steps (
            id INTEGER PRIMARY KEY,
            mission_id INTEGER NOT NULL REFERENCES missions(id),
            seq INTEGER NOT NULL, spec TEXT NOT NULL, label TEXT NOT NULL,
            status TEXT NOT NULL DEFAULT 'pending', detail TEXT,
            started_at REAL, ended_at REAL, x REAL, y REAL, theta REAL, docked INTEGER,
            UNIQUE (mission_id, seq)
        );
        CREATE INDEX missions_by_robot ON missions (robot, status);
        """,
    )


def _migrate_v8(conn: sqlite3.Connection) -> None:
    # Missions: a pause asked through the store, the mission that replaced this one, and a
    # repeat until stopped (the step rows are reused each round; a row's `round` says which
    # round its values are from).
    _run(
        conn,
        """
        ALTER TABLE missions ADD COLUMN pause_requested INTEGER NOT NULL DEFAULT 0;
        ALTER TABLE missions ADD COLUMN replaced_by INTEGER;
        ALTER TABLE missions ADD COLUMN forever INTEGER NOT NULL DEFAULT 0;
        ALTER TABLE missions ADD COLUMN round INTEGER NOT NULL DEFAULT 1;
        ALTER TABLE mission_steps ADD COLUMN round INTEGER NOT NULL DEFAULT 1;
        """,
    )


def _migrate_v9(conn: sqlite3.Connection) -> None:
    # Named locations belong to a map (the robot profile's): the places seeded so far are the
    # warehouse's. A name is unique on its map; SQLite cannot change a constraint in place.
    _run(
        conn,
        """
        CREATE TABLE locations_v9 (
            id INTEGER PRIMARY KEY,
            map TEXT NOT NULL DEFAULT 'warehouse',
            name TEXT NOT NULL COLLATE NOCASE,
            x REAL NOT NULL, y REAL NOT NULL, theta REAL NOT NULL DEFAULT 0,
            description TEXT NOT NULL DEFAULT '',
            created_at REAL NOT NULL, updated_at REAL NOT NULL,
            UNIQUE (map, name)
        );
        INSERT INTO locations_v9 (id, map, name, x, y, theta, description, created_at, updated_at)
            SELECT id, 'warehouse', name, x, y, theta, description, created_at, updated_at
            FROM locations;
        DROP TABLE locations;
        ALTER TABLE locations_v9 RENAME TO locations;
        """,
    )


def _migrate_v10(conn: sqlite3.Connection) -> None:
    # The E-STOP of one robot of a fleet (a row while latched); who controls each shared robot (a lease, one holder at a time, renewed by a heartbeat);
    # which robot of a fleet an event, a turn or an approval was about.
    _run(
        conn,
        """
        CREATE TABLE leases (
            robot TEXT PRIMARY KEY, token TEXT NOT NULL, who TEXT NOT NULL,
            host TEXT NOT NULL, pid INTEGER NOT NULL, taken_at REAL NOT NULL,
            seen_at REAL NOT NULL, taken_from TEXT
        );
        CREATE TABLE robot_estops (
            robot TEXT PRIMARY KEY, engaged_by TEXT NOT NULL, engaged_at REAL NOT NULL
        );
        ALTER TABLE events ADD COLUMN robot TEXT NOT NULL DEFAULT '';
        ALTER TABLE interactions ADD COLUMN robot TEXT NOT NULL DEFAULT '';
        ALTER TABLE approvals ADD COLUMN robot TEXT NOT NULL DEFAULT '';
        """,
    )


def _migrate_v11(conn: sqlite3.Connection) -> None:
    # A robot's own latch's last release: a press's late steps never undo a release made after it.
    _run(
        conn,
        """
        CREATE TABLE robot_estop_releases (
            robot TEXT PRIMARY KEY, released_by TEXT NOT NULL, released_at REAL NOT NULL
        );
        """,
    )


def _migrate_v12(conn: sqlite3.Connection) -> None:
    # Zones belong to a map with its places: keepout (no goal inside, no plan through) and speed
    # (a lower limit inside, m/s); corners a JSON list of [x, y] in the map frame.
    _run(
        conn,
        """
        CREATE TABLE zones (
            id INTEGER PRIMARY KEY,
            map TEXT NOT NULL DEFAULT 'warehouse',
            name TEXT NOT NULL COLLATE NOCASE,
            kind TEXT NOT NULL CHECK (kind IN ('keepout', 'speed')),
            corners TEXT NOT NULL, speed REAL,
            created_at REAL NOT NULL, updated_at REAL NOT NULL,
            UNIQUE (map, name)
        );
        """,
    )


# Ordered; the database's PRAGMA user_version counts how many have run. Each runs inside one
# transaction (Store._run_migrations): on a plain connection, with execute only.
MIGRATIONS = [
    _migrate_v1,
    _migrate_v2,
    _migrate_v3,
    _migrate_v4,
    _migrate_v5,
    _migrate_v6,
    _migrate_v7,
    _migrate_v8,
    _migrate_v9,
    _migrate_v10,
    _migrate_v11,
    _migrate_v12,
    _migrate_v13,
    _migrate_v14,
    _migrate_v15,
]
SCHEMA_VERSION = len(MIGRATIONS)
_OUR_TABLES = {
    "locations",
    "interactions",
    "commands",
    "events",
    "bench_runs",
    "bench_results",
    "estop",
    "approvals",
    "consoles",
    "missions",
    "mission_steps",
    "leases",
    "robot_estops",
    "robot_estop_releases",
    "zones",
    "watches",
    "alerts",
    "alert_episodes",
}


def check_database_file(path: Path) -> None:
    """Refuse anything that is not a SQLite file before SQLite touches it."""
    if path.is_dir():
        raise StoreError(f"database path {path} is a directory")
    if path.exists() and not path.is_file():
        raise StoreError(f"database path {path} is not a regular file")
    if path.exists():
        try:  # read, not stat: /proc files say size 0 and still have content
            with path.open("rb") as fh:
                header = fh.read(16)
        except OSError as exc:
            raise StoreError(f"cannot read {path}: {exc.strerror or exc}") from None
        if header and header != SQLITE_HEADER:
            raise StoreError(f"{path} is not a SQLite database; it was left untouched")

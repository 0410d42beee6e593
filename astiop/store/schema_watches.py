"""The watches' and alerts' migrations (13 to 15), apart from schema.py to keep it whole."""

from __future__ import annotations

import sqlite3


def _run(conn: sqlite3.Connection, script: str) -> None:
    from astiop.store.schema import _run as run  # schema.py imports this module

    run(conn, script)


def _migrate_v13(conn: sqlite3.Connection) -> None:
    # Watches (a condition on one robot's reading, said in plain language) and the alerts they
    # and the built-in ones fire: one row per event, whichever process saw it first (event_key
    # is the event's name and its episode, alert_episodes the episode each name is on).
    _run(
        conn,
        """
        CREATE TABLE watches (
            id INTEGER PRIMARY KEY,
            robot TEXT NOT NULL DEFAULT '',
            role TEXT NOT NULL, field TEXT NOT NULL,
            op TEXT NOT NULL CHECK (op IN ('<', '<=', '>', '>=')),
            threshold REAL NOT NULL, unit TEXT NOT NULL DEFAULT '',
            duration_s REAL NOT NULL DEFAULT 0,
            repeat TEXT NOT NULL DEFAULT 'once' CHECK (repeat IN ('once', 'every')),
            reaction TEXT NOT NULL DEFAULT 'notify' CHECK (reaction IN ('notify')),
            said TEXT NOT NULL DEFAULT '',
            created_at REAL NOT NULL,
            armed INTEGER NOT NULL DEFAULT 1
        );
        CREATE TABLE alerts (
            id INTEGER PRIMARY KEY,
            robot TEXT NOT NULL DEFAULT '',
            kind TEXT NOT NULL, message TEXT NOT NULL,
            reading TEXT, reading_age_s REAL,
            fired_at REAL NOT NULL,
            acknowledged_by TEXT, acknowledged_at REAL,
            watch_id INTEGER,
            event_key TEXT NOT NULL UNIQUE
        );
        CREATE INDEX alerts_by_robot ON alerts (robot, id);
        CREATE TABLE alert_episodes (
            name TEXT PRIMARY KEY, episode INTEGER NOT NULL DEFAULT 0
        );
        """,
    )


def _migrate_v14(conn: sqlite3.Connection) -> None:
    # A watch's reaction may move the robot: approved mission steps as JSON (watches/reactions.py)
    # beside 'notify'. SQLite changes a CHECK only by copying the table.
    _run(
        conn,
        """
        CREATE TABLE watches_v14 (
            id INTEGER PRIMARY KEY,
            robot TEXT NOT NULL DEFAULT '',
            role TEXT NOT NULL, field TEXT NOT NULL,
            op TEXT NOT NULL CHECK (op IN ('<', '<=', '>', '>=')),
            threshold REAL NOT NULL, unit TEXT NOT NULL DEFAULT '',
            duration_s REAL NOT NULL DEFAULT 0,
            repeat TEXT NOT NULL DEFAULT 'once' CHECK (repeat IN ('once', 'every')),
            reaction TEXT NOT NULL DEFAULT 'notify'
                CHECK (reaction = 'notify' OR (json_valid(reaction) AND repeat = 'once')),
            said TEXT NOT NULL DEFAULT '',
            created_at REAL NOT NULL,
            armed INTEGER NOT NULL DEFAULT 1
        );
        INSERT INTO watches_v14 SELECT * FROM watches;
        DROP TABLE watches;
        ALTER TABLE watches_v14 RENAME TO watches;
        """,
    )


def _migrate_v15(conn: sqlite3.Connection) -> None:
    # A watch on a named place keeps the place and its x, y on the robot's map (the robot's
    # distance to them is compared with the arrival tolerance); other watches leave them empty.
    _run(
        conn,
        """
        ALTER TABLE watches ADD COLUMN place TEXT NOT NULL DEFAULT '';
        ALTER TABLE watches ADD COLUMN x REAL NOT NULL DEFAULT 0;
        ALTER TABLE watches ADD COLUMN y REAL NOT NULL DEFAULT 0;
        """,
    )

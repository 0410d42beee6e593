"""SQLite store (WAL, sqlite-utils): schema migrations, locations, interactions, events, bench."""

from __future__ import annotations

import json
import math
import os
import re
import sqlite3
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import sqlite_utils
import yaml

from astiop.bounded import has_controls, one_line
from astiop.resources import data_path
from astiop.warehouse import Rect, default_map, fence_text, inside_fence

SQLITE_HEADER = b"SQLite format 3\x00"
BUSY_TIMEOUT_MS = 10_000  # how long a write waits for another process's
NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


class StoreError(Exception):
    """The database file cannot be used; it is left untouched."""


class LocationError(ValueError):
    """A location request is invalid; nothing was changed."""


@dataclass(frozen=True)
class Location:
    name: str
    x: float
    y: float
    theta: float  # rad
    description: str = ""

    def as_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "x": round(self.x, 4),
            "y": round(self.y, 4),
            "theta_deg": round(math.degrees(self.theta), 3),
            "description": self.description,
        }


def _seed_locations(db: sqlite_utils.Database) -> None:
    seeds = yaml.safe_load(data_path("locations.yaml").read_text(encoding="utf-8"))
    now = time.time()
    for s in seeds:
        db["locations"].insert(
            {
                "name": s["name"],
                "x": float(s["x"]),
                "y": float(s["y"]),
                "theta": math.radians(float(s.get("theta_deg", 0.0))),
                "description": s.get("description", ""),
                "created_at": now,
                "updated_at": now,
            }
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


def _migrate_v1(db: sqlite_utils.Database) -> None:
    db.conn.executescript(_SCHEMA_V1)
    _seed_locations(db)


def _migrate_v2(db: sqlite_utils.Database) -> None:
    # The E-STOP latch: one row, read by every astiop process on this database.
    db.conn.executescript(
        """
        CREATE TABLE estop (
            id INTEGER PRIMARY KEY CHECK (id = 1),
            engaged INTEGER NOT NULL DEFAULT 0,
            engaged_by TEXT, engaged_at REAL, released_by TEXT, released_at REAL
        );
        INSERT INTO estop (id, engaged) VALUES (1, 0);
        """
    )


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _migrate_v3(db: sqlite_utils.Database) -> None:
    # Grounded answers: the model's own text and why it was replaced; how a started goal ended.
    db.conn.executescript(
        """
        ALTER TABLE interactions ADD COLUMN model_answer TEXT;
        ALTER TABLE interactions ADD COLUMN grounding TEXT;
        ALTER TABLE interactions ADD COLUMN outcome TEXT;
        ALTER TABLE interactions ADD COLUMN outcome_at REAL;
        """
    )


def _migrate_v4(db: sqlite_utils.Database) -> None:
    # Every command astiop runs, with where it came from; the process behind a running turn.
    db.conn.executescript(
        """
        ALTER TABLE commands ADD COLUMN source TEXT;
        ALTER TABLE interactions ADD COLUMN pid INTEGER;
        """
    )


# Ordered; the database's PRAGMA user_version counts how many have run.
MIGRATIONS = [_migrate_v1, _migrate_v2, _migrate_v3, _migrate_v4]
SCHEMA_VERSION = len(MIGRATIONS)
_OUR_TABLES = {
    "locations",
    "interactions",
    "commands",
    "events",
    "bench_runs",
    "bench_results",
    "estop",
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


def _writable(path: Path) -> bool:
    """Whether astiop may write: the file (if it exists) and its folder (WAL's side files)."""
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if path.exists() and not os.access(path, os.W_OK):
        return False
    return os.access(folder, os.W_OK | os.X_OK)


class Store:
    """One connection per thread, all to the same file."""

    def __init__(self, path: Path | str, bounds: Rect | None = None):
        self.path = Path(path).expanduser()
        self.bounds = bounds or default_map().bounds  # named locations must lie inside
        self._local = threading.local()
        check_database_file(self.path)
        self.readonly = not _writable(self.path)
        if self.readonly and not self.path.exists():
            raise StoreError(f"cannot create {self.path}: its folder is not writable")
        if not self.readonly:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        self._check_integrity()
        self._migrate()
        if not self.readonly:
            self._mark_interrupted()

    # -- connections and schema -------------------------------------------------
    @property
    def db(self) -> sqlite_utils.Database:
        db = getattr(self._local, "db", None)
        if db is None:
            if self.readonly:  # reads work; any write fails, and _tx says so first
                conn = sqlite3.connect(f"{self.path.as_uri()}?mode=ro", uri=True, timeout=10)
            else:
                conn = sqlite3.connect(self.path, timeout=10)
            conn.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_MS}")  # SQLite retries, bounded
            db = sqlite_utils.Database(conn)
            self._local.db = db
        return db

    def _check_integrity(self) -> None:
        """PRAGMA quick_check before anything is written: a damaged file is refused whole."""
        if not self.path.exists() or self.path.stat().st_size == 0:
            return
        try:
            rows = self.db.conn.execute("PRAGMA quick_check(1)").fetchall()
        except sqlite3.DatabaseError as exc:
            self.close()
            why = one_line(exc, 160)
            raise StoreError(f"{self.path} is damaged ({why}); it was left untouched") from None
        if rows != [("ok",)]:
            self.close()
            why = one_line(rows[0][0], 160)
            raise StoreError(f"{self.path} is damaged ({why}); it was left untouched")

    @contextmanager
    def _tx(self) -> Iterator[None]:
        """One write transaction; a read-only or busy database and a broken write become one
        StoreError, a duplicate name a LocationError."""
        if self.readonly:
            raise StoreError(f"{self.path} is read-only: nothing was written")
        try:
            with self.db.conn:
                yield
        except sqlite3.IntegrityError as exc:
            if "UNIQUE" in str(exc) and "locations.name" in str(exc):
                raise LocationError("a location with that name already exists") from None
            raise StoreError(f"{self.path}: {exc}") from None
        except sqlite3.OperationalError as exc:
            raise StoreError(f"{self.path}: {exc}; nothing was written") from None

    def _mark_interrupted(self) -> None:
        """Turns left `running` by a process that is gone are marked `interrupted`."""
        rows = self.db.conn.execute(
            "SELECT id, pid FROM interactions WHERE status = 'running'"
        ).fetchall()
        dead = [i for i, pid in rows if pid is None or not _alive(pid)]
        if dead:
            with self._tx():
                self.db.conn.executemany(
                    "UPDATE interactions SET status = 'interrupted', "
                    "error = coalesce(error, 'the astiop process ended during the turn') "
                    "WHERE id = ?",
                    [(i,) for i in dead],
                )

    def _migrate(self) -> None:
        try:
            db = self.db
            version = db.conn.execute("PRAGMA user_version").fetchone()[0]
            tables = set(db.table_names())
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"{self.path} is not a usable SQLite database: {exc}") from None
        if version > SCHEMA_VERSION:
            raise StoreError(
                f"{self.path} has schema version {version}, newer than this astiop "
                f"understands ({SCHEMA_VERSION}); upgrade astiop. The file was left untouched"
            )
        if version == 0 and tables and not tables <= _OUR_TABLES:
            raise StoreError(f"{self.path} is a SQLite database of another application")
        if self.readonly:
            if version < SCHEMA_VERSION:
                raise StoreError(
                    f"{self.path} is read-only and needs an upgrade this astiop cannot write"
                )
            return
        try:
            db.conn.execute("PRAGMA journal_mode=WAL")
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"{self.path} cannot be written: {exc}") from None
        for index in range(version, SCHEMA_VERSION):
            with db.conn:
                MIGRATIONS[index](db)
                db.conn.execute(f"PRAGMA user_version = {index + 1}")

    def close(self) -> None:
        db = getattr(self._local, "db", None)
        if db is not None:
            db.conn.close()
            self._local.db = None

    # -- locations ----------------------------------------------------------------
    def list_locations(self) -> list[Location]:
        rows = self.db.query("SELECT * FROM locations ORDER BY name COLLATE NOCASE")
        return [_location(r) for r in rows]

    def copy_locations_from(self, other: Store) -> None:
        """This store's named locations become another's (a replay's or a bench run's own)."""
        rows = list(other.db.query("SELECT * FROM locations"))
        with self._tx():
            self.db.execute("DELETE FROM locations")
            if rows:
                self.db["locations"].insert_all(rows)

    def get_location(self, name: str) -> Location | None:
        rows = list(self.db.query("SELECT * FROM locations WHERE name = ? COLLATE NOCASE", [name]))
        return _location(rows[0]) if rows else None

    def require_location(self, name: str) -> Location:
        loc = self.get_location(name)
        if loc is None:
            known = ", ".join(loc.name for loc in self.list_locations()) or "none"
            raise LocationError(f"no location named '{name}' (known: {known})")
        return loc

    def _check_new_name(self, name: str) -> None:
        if not NAME_RE.match(name):
            raise LocationError(
                f"invalid location name '{name}': use 1-64 letters, digits, '_' or '-'"
            )
        if self.get_location(name) is not None:
            raise LocationError(f"a location named '{name}' already exists (names ignore case)")

    def _check_pose(self, x: float, y: float, theta: float) -> None:
        if not all(math.isfinite(v) for v in (x, y, theta)):
            raise LocationError("x, y and theta must be finite numbers")
        if not inside_fence(self.bounds, x, y):
            raise LocationError(
                f"({x:g}, {y:g}) is outside the geofence ({fence_text(self.bounds)})"
            )

    def add_location(
        self, name: str, x: float, y: float, theta: float = 0.0, description: str = ""
    ) -> Location:
        self._check_new_name(name)
        self._check_pose(x, y, theta)
        if has_controls(description) or len(description) > 500:
            raise LocationError("a description is plain text of at most 500 characters")
        theta = math.atan2(math.sin(theta), math.cos(theta))
        now = time.time()
        with self._tx():
            self.db["locations"].insert(
                {
                    "name": name,
                    "x": x,
                    "y": y,
                    "theta": theta,
                    "description": description,
                    "created_at": now,
                    "updated_at": now,
                }
            )
        return Location(name, x, y, theta, description)

    def rename_location(self, old: str, new: str) -> Location:
        loc = self.require_location(old)
        if new.lower() != loc.name.lower():
            self._check_new_name(new)
        elif not NAME_RE.match(new):
            raise LocationError(f"invalid location name '{new}'")
        with self._tx():
            self.db.conn.execute(
                "UPDATE locations SET name = ?, updated_at = ? WHERE name = ? COLLATE NOCASE",
                [new, time.time(), loc.name],
            )
        return Location(new, loc.x, loc.y, loc.theta, loc.description)

    def remove_location(self, name: str) -> Location:
        loc = self.require_location(name)
        with self._tx():
            self.db.conn.execute("DELETE FROM locations WHERE name = ? COLLATE NOCASE", [loc.name])
        return loc

    # -- interactions, commands, events --------------------------------------------
    def start_interaction(self, *, model: str, mode: str, prompt: str, session: str = "") -> int:
        with self._tx():
            row = self.db["interactions"].insert(
                {
                    "session": session,
                    "started_at": time.time(),
                    "model": model,
                    "mode": mode,
                    "prompt": prompt,
                    "status": "running",
                    "pid": os.getpid(),
                }
            )
        return int(row.last_pk)

    def update_interaction(self, interaction_id: int, **fields: Any) -> None:
        if "raw_replies" in fields and not isinstance(fields["raw_replies"], str):
            fields["raw_replies"] = json.dumps(fields["raw_replies"])
        with self._tx():
            self.db["interactions"].update(interaction_id, fields)

    def add_command(self, interaction_id: int | None, **fields: Any) -> int:
        record = {"interaction_id": interaction_id, "created_at": time.time(), **fields}
        if "values" in record and not isinstance(record["values"], (str, type(None))):
            record["values"] = json.dumps(record["values"], default=str)
        with self._tx():
            return int(self.db["commands"].insert(record).last_pk)

    def add_event(
        self, kind: str, message: str, *, severity: str = "info", sim_t: float | None = None
    ) -> None:
        with self._tx():
            self.db["events"].insert(
                {
                    "t": time.time(),
                    "sim_t": sim_t,
                    "kind": kind,
                    "severity": severity,
                    "message": message,
                }
            )

    def interactions(self, limit: int = 500) -> list[dict[str, Any]]:
        return list(self.db.query("SELECT * FROM interactions ORDER BY id DESC LIMIT ?", [limit]))

    def commands_for(self, interaction_id: int) -> list[dict[str, Any]]:
        return list(
            self.db.query(
                "SELECT * FROM commands WHERE interaction_id = ? ORDER BY seq, id", [interaction_id]
            )
        )

    def commands_by_interaction(self, ids: list[int]) -> dict[int, list[dict[str, Any]]]:
        found: dict[int, list[dict[str, Any]]] = {i: [] for i in ids}
        if ids:
            marks = ",".join("?" * len(ids))
            for row in self.db.query(
                f"SELECT * FROM commands WHERE interaction_id IN ({marks}) ORDER BY seq, id", ids
            ):
                found[row["interaction_id"]].append(row)
        return found

    # -- the E-STOP latch --------------------------------------------------------------
    def estop_latch(self) -> dict[str, Any] | None:
        """The latch while engaged (who, when), else None."""
        row = self.db.conn.execute(
            "SELECT engaged, engaged_by, engaged_at FROM estop WHERE id = 1"
        ).fetchone()
        if row and row[0]:
            return {"by": row[1], "at": row[2]}
        return None

    def latch_estop(self, who: str) -> None:
        with self._tx():
            self.db.conn.execute(
                "UPDATE estop SET engaged = 1, engaged_by = ?, engaged_at = ? WHERE id = 1",
                [who, time.time()],
            )

    def release_estop(self, who: str) -> None:
        with self._tx():
            self.db.conn.execute(
                "UPDATE estop SET engaged = 0, released_by = ?, released_at = ? WHERE id = 1",
                [who, time.time()],
            )

    def newest_interaction_id(self) -> int:
        return self.db.execute("SELECT max(id) FROM interactions").fetchone()[0] or 0

    def finished_interactions_after(self, interaction_id: int) -> list[dict[str, Any]]:
        """Turns that ended after `interaction_id`, with their commands (for recording)."""
        rows = list(
            self.db.query(
                "SELECT id, prompt, model, mode, answer, grounding, total_s, status "
                "FROM interactions WHERE id > ? AND status != 'running' ORDER BY id",
                [interaction_id],
            )
        )
        for row in rows:
            row["commands"] = list(
                self.db.query(
                    "SELECT command, valid, executed, reason, source FROM commands "
                    "WHERE interaction_id = ? ORDER BY seq",
                    [row["id"]],
                )
            )
        return rows

    def add_recorded_interaction(self, turn: dict[str, Any], started_at: float) -> int:
        """A turn read back from a recording (replay), with its commands."""
        keys = ("prompt", "model", "mode", "answer", "grounding", "total_s", "status")
        with self._tx():
            row = {k: turn.get(k) for k in keys}
            row.update(session="replay", started_at=started_at, prompt=str(row["prompt"] or ""))
            row.update(model=str(row["model"] or ""), mode=str(row["mode"] or ""))
            interaction_id = int(self.db["interactions"].insert(row).last_pk)
            for seq, cmd in enumerate(turn.get("commands") or []):
                keep = ("command", "valid", "executed", "reason", "source")
                self.db["commands"].insert(
                    {"interaction_id": interaction_id, "created_at": started_at, "seq": seq}
                    | {k: cmd.get(k) for k in keep}
                )
        return interaction_id

    def events(self, limit: int = 500) -> list[dict[str, Any]]:
        return list(self.db.query("SELECT * FROM events ORDER BY id DESC LIMIT ?", [limit]))

    # -- benchmark runs ----------------------------------------------------------------
    def create_bench_run(self, stage: int, config: dict[str, Any]) -> int:
        with self._tx():
            row = self.db["bench_runs"].insert(
                {
                    "started_at": time.time(),
                    "stage": stage,
                    "models": json.dumps(config["models"]),
                    "modes": json.dumps(config["modes"]),
                    "seed": config["seed"],
                    "case_limit": config["limit"],
                    "status": "running",
                    "config": json.dumps(config),
                }
            )
        return int(row.last_pk)

    def bench_run(self, run_id: int) -> dict[str, Any] | None:
        rows = list(self.db.query("SELECT * FROM bench_runs WHERE id = ?", [run_id]))
        return rows[0] if rows else None

    def bench_runs(self) -> list[dict[str, Any]]:
        return list(
            self.db.query(
                "SELECT r.*, (SELECT count(*) FROM bench_results b WHERE b.run_id = r.id) "
                "AS results FROM bench_runs r ORDER BY r.id DESC"
            )
        )

    def bench_results(self, run_id: int) -> list[dict[str, Any]]:
        return list(
            self.db.query("SELECT * FROM bench_results WHERE run_id = ? ORDER BY id", [run_id])
        )

    def add_bench_result(self, run_id: int, row: dict[str, Any]) -> None:
        with self._tx():
            self.db["bench_results"].insert(
                {"run_id": run_id, **row, "created_at": time.time()}, replace=True
            )

    def end_bench_run(self, run_id: int, status: str) -> None:
        """done or interrupted; an interrupted run keeps its results and can resume."""
        with self._tx():
            self.db["bench_runs"].update(run_id, {"status": status, "finished_at": time.time()})


def _location(row: dict[str, Any]) -> Location:
    return Location(row["name"], row["x"], row["y"], row["theta"], row["description"] or "")

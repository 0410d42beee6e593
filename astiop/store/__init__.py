"""SQLite store (WAL, sqlite-utils): one file, one connection per thread, every SQL statement
of astiop behind a named method (locations, the journal, the benchmark)."""

from __future__ import annotations

import os
import random
import sqlite3
import threading
import time
from pathlib import Path

from astiop.bounded import one_line
from astiop.store.approvals import ApprovalTables
from astiop.store.bench import BenchTables
from astiop.store.connection import BUSY_TIMEOUT_MS
from astiop.store.journal import JournalTables
from astiop.store.leases import LeaseTables
from astiop.store.liveness import _alive
from astiop.store.locations import LocationTables
from astiop.store.missions import MissionTables
from astiop.store.records import Location, LocationError, StoreError
from astiop.store.schema import (
    _OUR_TABLES,
    MIGRATIONS,
    SCHEMA_VERSION,
    check_database_file,
)
from astiop.store.tallies import TallyTables
from astiop.store.watches import WatchTables
from astiop.store.zones import ZoneTables
from astiop.warehouse import Rect, default_map

__all__ = ["SCHEMA_VERSION", "Location", "LocationError", "Store", "StoreError"]


def _writable(path: Path) -> bool:
    """Whether astiop may write: the file (if it exists) and its folder (WAL's side files)."""
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if path.exists() and not os.access(path, os.W_OK):
        return False
    return os.access(folder, os.W_OK | os.X_OK)


class Store(
    LocationTables,
    ZoneTables,
    JournalTables,
    BenchTables,
    ApprovalTables,
    MissionTables,
    LeaseTables,
    WatchTables,
    TallyTables,
):
    """One connection per thread, all to the same file."""

    def __init__(self, path: Path | str, bounds: Rect | None = None):
        self.path = Path(path).expanduser()
        self.bounds = bounds or default_map().bounds  # named locations must lie inside (use_map)
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
    def schema_version(self) -> int:
        """How many of the schema's migrations this file has had."""
        return self.db.conn.execute("PRAGMA user_version").fetchone()[0]

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
        self.mark_missions_interrupted()

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
        self._enter_wal(db.conn)
        if version < SCHEMA_VERSION:
            self._run_migrations()

    def _enter_wal(self, conn: sqlite3.Connection) -> None:
        """PRAGMA journal_mode=WAL, outside any transaction (SQLite refuses it inside one).
        Switching needs the file to itself, and SQLite answers "locked" at once, without its
        busy wait, when another process opening a new file holds it: retried, bounded."""
        deadline = time.monotonic() + BUSY_TIMEOUT_MS / 1000
        while True:
            try:
                conn.execute("PRAGMA journal_mode=WAL")
                return
            except sqlite3.OperationalError as exc:
                if "locked" not in str(exc) or time.monotonic() > deadline:
                    raise StoreError(f"{self.path} cannot be written: {exc}") from None
            except sqlite3.DatabaseError as exc:
                raise StoreError(f"{self.path} cannot be written: {exc}") from None
            time.sleep(random.uniform(0.005, 0.05))  # apart from the others trying

    def _run_migrations(self) -> None:
        """Each migration in one transaction, on a connection of its own in autocommit mode (no
        implicit BEGIN or COMMIT from Python): a process killed inside one leaves the version
        before it. The version is read again under the write lock, as another process opening
        the same file may have migrated it meanwhile."""
        conn = sqlite3.connect(self.path, timeout=BUSY_TIMEOUT_MS / 1000, isolation_level=None)
        version = None
        try:
            while True:
                conn.execute("BEGIN IMMEDIATE")
                version = conn.execute("PRAGMA user_version").fetchone()[0]
                if version >= SCHEMA_VERSION:  # done, by this process or another
                    conn.execute("ROLLBACK")
                    break
                MIGRATIONS[version](conn)
                conn.execute(f"PRAGMA user_version = {version + 1}")
                conn.execute("COMMIT")
        except sqlite3.DatabaseError as exc:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            at = "" if version is None else f"; it was left at schema version {version}"
            raise StoreError(f"{self.path}: the schema upgrade failed ({exc}){at}") from None
        finally:
            conn.close()
        if version > SCHEMA_VERSION:
            raise StoreError(
                f"{self.path} was upgraded meanwhile to schema version {version}, newer than "
                f"this astiop understands ({SCHEMA_VERSION}); upgrade astiop"
            )

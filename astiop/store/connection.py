"""The store's connection to its file, one per thread, and its write transaction: what every
group of tables (`LocationTables`, `JournalTables`, ...) works through. `Store` sets the file's
path and whether it may be written."""

from __future__ import annotations

import os
import sqlite3
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import sqlite_utils

from astiop.store.records import LocationError, StoreError

BUSY_TIMEOUT_MS = 10_000  # how long a write waits for another process's


def _read_only_uri(path: Path) -> str:
    """mode=ro; and immutable where SQLite could not make a WAL file's shared-memory file (no
    -shm beside it, in a folder astiop may not write): it is then read as it stands on disk."""
    shm = path.with_name(path.name + "-shm")
    if not shm.exists() and not os.access(path.parent, os.W_OK | os.X_OK):
        return f"{path.as_uri()}?mode=ro&immutable=1"
    return f"{path.as_uri()}?mode=ro"


class Connection:
    """One SQLite connection per thread to `path`; read-only when `readonly`."""

    path: Path
    readonly: bool
    _local: threading.local

    @property
    def db(self) -> sqlite_utils.Database:
        db = getattr(self._local, "db", None)
        if db is None:
            if self.readonly:  # reads work; any write fails, and _tx says so first
                conn = sqlite3.connect(_read_only_uri(self.path), uri=True, timeout=10)
            else:
                conn = sqlite3.connect(self.path, timeout=10)
            conn.execute(f"PRAGMA busy_timeout={BUSY_TIMEOUT_MS}")  # SQLite retries, bounded
            db = sqlite_utils.Database(conn)
            self._local.db = db
        return db

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

    def close(self) -> None:
        db = getattr(self._local, "db", None)
        if db is not None:
            db.conn.close()
            self._local.db = None


def row_id(value: object) -> int:
    """The id SQLite gave the row just inserted (`lastrowid`, `last_pk`): never None after an
    insert into a table with a rowid."""
    if not isinstance(value, int):
        raise StoreError(f"the row was not written (its id is {value!r})")
    return value

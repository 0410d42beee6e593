"""The E-STOP latch's SQL, and its writing by `astiop estop` before anything else is imported.

The store (`store/journal.py`) latches with the same statements. `astiop estop` latches here
first, with the standard library alone: importing the store takes ~0.2 s (sqlite-utils, numpy),
and every other astiop process ends what it has in flight as soon as the latch is written.
"""

from __future__ import annotations

import os
import sqlite3
import time
from pathlib import Path

# A latch already engaged keeps who engaged it and when (SET reads the row as it was). A press
# latches only if no release was made after it: a press's late steps never undo a later release.
LATCH = (
    "UPDATE estop SET engaged_by = CASE WHEN engaged = 1 THEN engaged_by ELSE ? END, "
    "engaged_at = CASE WHEN engaged = 1 THEN engaged_at ELSE ? END, engaged = 1 "
    "WHERE id = 1 AND COALESCE(released_at, 0) < ?"
)
RELEASE = "UPDATE estop SET engaged = 0, released_by = ?, released_at = ? WHERE id = 1"
WAIT_S = 0.05  # for another process's write: never in the robot's way; the full path latches
# when this process pressed the E-STOP (`astiop estop`): each of its steps is that one press
PRESSED_AT: float | None = None


def pressed_at() -> float:
    """The time of this process's press, taken once (the first step that asks)."""
    global PRESSED_AT
    if PRESSED_AT is None:
        PRESSED_AT = time.time()
    return PRESSED_AT


def _configured_db(env: dict[str, str]) -> Path | None:
    """`db` in the settings file, as config.config_path finds it (None: not set, unreadable)."""
    import platformdirs

    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib

    if env.get("ASTIOP_CONFIG"):
        file = Path(env["ASTIOP_CONFIG"]).expanduser()
    else:
        file = platformdirs.user_config_path("astiop") / "config.toml"
    try:
        value = tomllib.loads(file.read_text(encoding="utf-8")).get("db")
    except (OSError, ValueError):
        return None
    return Path(value) if isinstance(value, str) and value else None


def db_path(args: list[str], env: dict[str, str] | None = None) -> Path:
    """The database a command line will use, read as the settings read it: `--db`, then
    ASTIOP_DB, then the settings file, then the default."""
    env = dict(os.environ) if env is None else env
    for i, token in enumerate(args):
        if token == "--db" and i + 1 < len(args):
            return Path(args[i + 1]).expanduser()
        if token.startswith("--db="):
            return Path(token[5:]).expanduser()
    named = [v for k, v in env.items() if k.upper() == "ASTIOP_DB" and v]  # as the settings
    if named:
        return Path(named[-1]).expanduser()
    configured = _configured_db(env)
    if configured is not None:
        return configured.expanduser()
    import platformdirs

    return platformdirs.user_data_path("astiop") / "astiop.db"


def latch_early(args: list[str], who: str = "estop") -> bool:
    """Latch the E-STOP in the command line's database, if it exists, now; False if it cannot be
    done here (no file yet, an older schema, a lock held too long, a path it cannot read): the
    full path latches it then, and says why it could not."""
    try:
        path = db_path(args)
        if not path.is_file():
            return False
        at = pressed_at()
        conn = sqlite3.connect(path, timeout=WAIT_S)
        try:
            with conn:
                written = conn.execute(LATCH, (who, at, at)).rowcount
        finally:
            conn.close()
    except Exception:  # noqa: BLE001 - never in the way of the full path
        return False
    return written == 1

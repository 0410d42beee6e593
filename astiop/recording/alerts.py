"""The alerts in a session: each alert any process on the database fired while it was recorded
(a console, `astiop watch run`, `astiop serve`'s), written once on /astiop/alerts as stored:
its robot, kind, message, the reading and its age, the watch that fired it."""

from __future__ import annotations

import time
from typing import Any

TOPIC = "/astiop/alerts"
POLL_S = 0.25  # the store is read at most this often (the recorder polls at 20 Hz)
# each field of the alert as stored, and its JSON type
FIELDS: dict[str, str | list[str]] = {
    "id": "integer", "robot": "string", "kind": "string", "message": "string",
    "reading": ["string", "null"], "reading_age_s": ["number", "null"], "fired_at": "number",
    "watch_id": ["integer", "null"],
}  # fmt: skip
SCHEMA = {
    "type": "object",
    "title": "astiop alert",
    "properties": {name: {"type": kind} for name, kind in FIELDS.items()},
}


class AlertLog:
    """The alerts written since the last look, as records to write (none of those written
    before the recording began)."""

    def __init__(self, store):
        self.store = store
        newest = store.list_alerts(limit=1) if store is not None else []
        self._after = newest[-1]["id"] if newest else 0
        self._looked = 0.0

    def poll(self) -> list[dict[str, Any]]:
        if self.store is None or time.monotonic() - self._looked < POLL_S:
            return []
        self._looked = time.monotonic()
        rows = self.store.list_alerts(after_id=self._after, limit=500)
        if rows:
            self._after = rows[-1]["id"]
        return [{k: row[k] for k in FIELDS} for row in rows]

"""A stretch of time exported from what astiop keeps: the store's turns and events, and the
robot's messages from the recordings that cover it, as MCAP or JSON lines.

Times are wall-clock: a recording made on the simulator is logged on sim time and placed in
wall time by the clocks its metadata gives at its start.
"""

from __future__ import annotations

import json
import re
import time
from datetime import datetime
from pathlib import Path
from typing import Any

from mcap.writer import Writer

from astiop.recording.reader import Recording
from astiop.recording.schemas import JSON_SCHEMAS
from astiop.recording.writer import RecordingError

RELATIVE = re.compile(r"^-(\d+(?:\.\d+)?)([smhd])$")
UNITS = {"s": 1, "m": 60, "h": 3600, "d": 86400}


class ExportError(ValueError):
    """The export cannot be made as asked; one line says why."""


def parse_time(text: str, now: float | None = None) -> float:
    """'now', '-30s'/'-10m'/'-2h'/'-1d', epoch seconds, ISO 8601 (local time when no zone is
    given: '2026-11-22T14:05', '2026-11-22 14:05:30+00:00'), or 'HH:MM[:SS]' today."""
    now = time.time() if now is None else now
    value = text.strip()
    if value == "now":
        return now
    if m := RELATIVE.match(value):
        return now - float(m.group(1)) * UNITS[m.group(2)]
    if re.fullmatch(r"\d{9,11}(\.\d+)?", value):
        return float(value)
    if re.fullmatch(r"\d{1,2}:\d{2}(:\d{2})?", value):
        value = datetime.fromtimestamp(now).strftime("%Y-%m-%d ") + value
    try:
        return datetime.fromisoformat(value).timestamp()
    except ValueError:
        raise ExportError(
            f"cannot read the time '{text}': use now, -10m, -2h, 14:05, 2026-11-22T14:05 "
            "or epoch seconds"
        ) from None


def recordings_between(
    folder: Path, t0: float, t1: float, exclude: Path | None = None
) -> tuple[list[Recording], list[str]]:
    """The recordings in folder whose span meets [t0, t1]; and the files that could not be read."""
    found, skipped = [], []
    for path in sorted(Path(folder).glob("*.mcap")) if Path(folder).is_dir() else []:
        if exclude is not None and path.resolve() == Path(exclude).resolve():
            continue
        try:
            rec = Recording(path)
        except RecordingError as exc:
            skipped.append(str(exc))
            continue
        offset = rec.wall_offset_s()
        if rec.start_ns / 1e9 + offset <= t1 and rec.end_ns / 1e9 + offset >= t0:
            found.append(rec)
    return found, skipped


def _robot_messages(recordings: list[Recording], t0: float, t1: float):
    """(wall ns, recording, channel, index) of every robot message in the window."""
    for rec in recordings:
        offset_ns = round(rec.wall_offset_s() * 1e9)
        lo, hi = round(t0 * 1e9) - offset_ns, round(t1 * 1e9) - offset_ns
        for ch in rec.channels.values():
            if ch.encoding != "cdr":
                continue  # turns and events come from the store, which holds them all
            for i, t_ns in enumerate(ch.times):
                if lo <= t_ns <= hi:
                    yield t_ns + offset_ns, rec, ch, i


def _journal(store, t0: float, t1: float) -> list[tuple[float, str, dict[str, Any]]]:
    rows = [
        (it["started_at"], "/astiop/interactions", it) for it in store.interactions_between(t0, t1)
    ]
    rows += [(ev["t"], "/astiop/events", ev) for ev in store.events_between(t0, t1)]
    return rows


def export_jsonl(out: Path, store, recordings: list[Recording], t0: float, t1: float) -> dict:
    lines: list[tuple[float, dict]] = []
    for t, topic, row in _journal(store, t0, t1):
        lines.append((t, {"t": t, "topic": topic, "source": "store", "data": row}))
    for t_ns, rec, ch, i in _robot_messages(recordings, t0, t1):
        item = {"t": t_ns / 1e9, "topic": ch.topic, "type": ch.type, "source": rec.path.name}
        lines.append((t_ns / 1e9, item | {"data": ch.message(i)}))
    lines.sort(key=lambda pair: pair[0])
    counts: dict[str, int] = {}
    with Path(out).open("w", encoding="utf-8") as fh:
        for _t, item in lines:
            fh.write(json.dumps(item, default=str) + "\n")
            counts[item["topic"]] = counts.get(item["topic"], 0) + 1
    return counts


def export_mcap(out: Path, store, recordings: list[Recording], t0: float, t1: float) -> dict:
    items: list[tuple[int, str, bytes]] = []
    with Path(out).open("wb") as fh:
        writer = Writer(fh)
        writer.start(profile="ros2", library="astiop export")
        backends = {rec.backend for rec in recordings} or {"export"}
        backend = backends.pop() if len(backends) == 1 else "export"
        writer.add_metadata("astiop", {"backend": backend, "robot_t0": "0", "wall_t0": "0"})
        channels: dict[str, int] = {}
        for t_ns, _rec, ch, i in _robot_messages(recordings, t0, t1):
            if ch.topic not in channels:
                schema = writer.register_schema(ch.type, ch.schema_encoding, ch.schema_data)
                channels[ch.topic] = writer.register_channel(ch.topic, "cdr", schema)
            items.append((t_ns, ch.topic, ch.data[i]))
        for t, topic, row in _journal(store, t0, t1):
            if topic not in channels:
                data = json.dumps(JSON_SCHEMAS[topic]).encode()
                schema = writer.register_schema(topic.split("/")[-1], "jsonschema", data)
                channels[topic] = writer.register_channel(topic, "json", schema)
            items.append((round(t * 1e9), topic, json.dumps(row, default=str).encode()))
        items.sort(key=lambda item: item[0])
        counts: dict[str, int] = {}
        for t_ns, topic, data in items:
            writer.add_message(channels[topic], t_ns, data, t_ns)
            counts[topic] = counts.get(topic, 0) + 1
        writer.finish()
    return counts

"""A recording read back: every message indexed by log time, ROS 2 messages decoded on demand.

Reading keeps the raw bytes only (a 10-minute session opens in well under a second); a message
is decoded by `mcap-ros2-support` when it is first asked for.
"""

from __future__ import annotations

import bisect
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcap.records import Channel as McapChannel
from mcap.records import Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap_ros2.decoder import DecoderFactory

from astiop.recording.writer import RecordingError
from astiop.ros2.message_objects import plain


@dataclass
class Channel:
    topic: str
    encoding: str  # cdr | json
    type: str  # the schema's name: pkg/msg/Name, or the JSON schema's title
    schema_encoding: str = ""  # ros2msg | jsonschema
    schema_data: bytes = b""
    times: list[int] = field(default_factory=list)  # log time, ns, ascending
    data: list[bytes] = field(default_factory=list)
    decode: Any = None
    cache: dict[int, dict] = field(default_factory=dict)

    def message(self, index: int) -> dict:
        if index not in self.cache:
            raw = self.data[index]
            value = json.loads(raw) if self.encoding == "json" else plain(self.decode(raw))
            if len(self.cache) > 64:
                self.cache.clear()
            self.cache[index] = value
        return self.cache[index]

    def index_at(self, t_ns: int) -> int:
        """The last message logged at or before t_ns (-1: none yet)."""
        return bisect.bisect_right(self.times, t_ns) - 1


class Recording:
    def __init__(self, path: Path | str):
        self.path = Path(path)
        self.channels: dict[str, Channel] = {}
        self.metadata: dict[str, str] = {}
        self.cut = False  # the file ends mid-record (a killed recording): read up to there
        factory = DecoderFactory()
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        try:
            with self.path.open("rb") as fh:
                records = StreamReader(fh, skip_magic=False).records
                while True:
                    try:
                        record = next(records)
                    except StopIteration:
                        break
                    except Exception:  # the mcap reader raises its own kinds at a cut
                        self.cut = True
                        break
                    if isinstance(record, Schema):
                        schemas[record.id] = record
                    elif isinstance(record, McapChannel) and record.topic not in self.channels:
                        schema = schemas.get(record.schema_id)
                        ch = Channel(record.topic, record.message_encoding, "")
                        if schema is not None:
                            ch.type, ch.schema_encoding = schema.name, schema.encoding
                            ch.schema_data = schema.data
                        if record.message_encoding == "cdr" and schema is not None:
                            ch.decode = factory.decoder_for("cdr", schema)
                        self.channels[record.topic] = ch
                        channels[record.id] = ch
                    elif isinstance(record, McapChannel):
                        channels[record.id] = self.channels[record.topic]
                    elif isinstance(record, Message) and record.channel_id in channels:
                        ch = channels[record.channel_id]
                        ch.times.append(record.log_time)
                        ch.data.append(record.data)
                    elif isinstance(record, Metadata) and record.name == "astiop":
                        self.metadata = dict(record.metadata)
        except OSError as exc:
            raise RecordingError(f"cannot read {self.path}: {exc.strerror or exc}") from None
        if not self.channels and self.cut:
            raise RecordingError(f"{self.path}: not an MCAP recording")
        for ch in self.channels.values():  # log order across chunks, kept per topic
            if any(b < a for a, b in zip(ch.times, ch.times[1:])):
                order = sorted(range(len(ch.times)), key=ch.times.__getitem__)
                ch.times = [ch.times[i] for i in order]
                ch.data = [ch.data[i] for i in order]
        robot = [c for c in self.channels.values() if c.encoding == "cdr" and c.times]
        if not robot:
            raise RecordingError(f"{self.path}: the recording holds no robot message")
        self.start_ns = min(c.times[0] for c in robot)
        self.end_ns = max(c.times[-1] for c in robot)

    @property
    def duration_s(self) -> float:
        return (self.end_ns - self.start_ns) / 1e9

    @property
    def backend(self) -> str:
        return self.metadata.get("backend", "")

    def wall_offset_s(self) -> float:
        """Add to a log time (s) to get wall time: non-zero for sim-time recordings."""
        try:
            return float(self.metadata["wall_t0"]) - float(self.metadata["robot_t0"])
        except (KeyError, ValueError):
            return 0.0

    def latest(self, topics, t_ns: int) -> dict[str, dict]:
        """The last message of each topic logged at or before t_ns."""
        out = {}
        for topic in topics:
            ch = self.channels.get(topic)
            if ch is not None and (i := ch.index_at(t_ns)) >= 0:
                out[topic] = ch.message(i)
        return out

    def count_between(self, topic: str, t0_ns: int, t1_ns: int) -> int:
        """How many messages of a topic have t0 < log time <= t1 (none is decoded)."""
        ch = self.channels.get(topic)
        if ch is None:
            return 0
        lo, hi = self._span(ch, t0_ns, t1_ns)
        return hi - lo

    @staticmethod
    def _span(ch: Channel, t0_ns: int, t1_ns: int) -> tuple[int, int]:
        return bisect.bisect_right(ch.times, t0_ns), bisect.bisect_right(ch.times, t1_ns)

    def counts(self) -> dict[str, int]:
        return {topic: len(ch.times) for topic, ch in self.channels.items()}


def fleet_of(recording: Recording) -> list[tuple[str, str]]:
    """A fleet session's robots, (name, namespace); [] for one robot's."""
    try:
        robots = json.loads(recording.metadata.get("fleet", "[]"))
        return [(str(name), str(ns)) for name, ns in robots]
    except (ValueError, TypeError):
        return []


class RobotView(Recording):
    """One robot of a fleet recording, read as if it were the whole recording: its topics by
    their names inside its namespace ("/astibot_2/odom" as "/odom"), its own events; the store's
    records (the turns, the missions) with the first robot only (`shared`), never twice."""

    def __init__(self, recording: Recording, namespace: str, shared: bool):
        # read already: the recording's channels seen through the namespace, nothing re-read
        self.path, self.metadata, self.cut = recording.path, recording.metadata, recording.cut
        self.start_ns, self.end_ns = recording.start_ns, recording.end_ns
        inside = len(namespace)
        self.channels = {
            topic[inside:]: ch
            for topic, ch in recording.channels.items()
            if topic.startswith(namespace + "/")
        }
        if shared:
            for topic in ("/astiop/interactions", "/astiop/mission"):
                if topic in recording.channels:
                    self.channels[topic] = recording.channels[topic]

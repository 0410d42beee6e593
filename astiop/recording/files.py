"""A recording file read whole: its summary, and the repair of one cut off."""

from __future__ import annotations

from pathlib import Path

from mcap.reader import make_reader
from mcap.records import Channel, Message, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import Writer

from astiop.recording.writer import RecordingError


def summary(path: Path) -> dict[str, int]:
    """Message count per topic, from the file's own summary."""
    try:
        with Path(path).open("rb") as fh:
            info = make_reader(fh).get_summary()
    except Exception as exc:  # the mcap reader raises its own kinds
        raise RecordingError(f"{path}: not a readable MCAP file ({exc})") from None
    if info is None or info.statistics is None:
        raise RecordingError(f"{path}: the file has no summary (try --repair)")
    return {
        info.channels[cid].topic: count
        for cid, count in info.statistics.channel_message_counts.items()
    }


def repair(path: Path, out: Path) -> dict[str, int]:
    """Copy every whole record of a cut-off recording into a new, finished file."""
    schemas: dict[int, int] = {}
    channels: dict[int, int] = {}
    counts: dict[str, int] = {}
    topics: dict[int, str] = {}
    with Path(path).open("rb") as src, Path(out).open("wb") as dst:
        writer = Writer(dst)
        writer.start(profile="ros2", library="astiop repair")
        try:
            for record in StreamReader(src, skip_magic=False).records:
                if isinstance(record, Schema) and record.id not in schemas:
                    schemas[record.id] = writer.register_schema(
                        record.name, record.encoding, record.data
                    )
                elif isinstance(record, Channel) and record.id not in channels:
                    channels[record.id] = writer.register_channel(
                        record.topic, record.message_encoding, schemas.get(record.schema_id, 0)
                    )
                    topics[record.id] = record.topic
                elif isinstance(record, Message) and record.channel_id in channels:
                    writer.add_message(
                        channels[record.channel_id],
                        record.log_time,
                        record.data,
                        record.publish_time,
                    )
                    topic = topics[record.channel_id]
                    counts[topic] = counts.get(topic, 0) + 1
        except Exception:  # the cut: everything before it is kept
            pass
        writer.finish()
    if not counts:
        raise RecordingError(f"{path}: no whole message could be recovered")
    return counts

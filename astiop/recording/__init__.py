"""Sessions as MCAP: written while the robot runs (`writer`), read back for replay and export."""

from astiop.recording.files import repair, summary
from astiop.recording.schemas import ros2msg
from astiop.recording.writer import FLUSH_S, RecordingError, SessionRecorder, default_path

__all__ = [
    "FLUSH_S",
    "RecordingError",
    "SessionRecorder",
    "default_path",
    "repair",
    "ros2msg",
    "summary",
]

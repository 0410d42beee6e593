"""An alert's fields as the screens show them (the Alerts screen, F8, and the Logs, F3)."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any


def when(t: float | None) -> str:
    """A local time to the second, "-" for none."""
    return time.strftime("%m-%d %H:%M:%S", time.localtime(t)) if t else "-"


def reading_text(alert: Mapping[str, Any]) -> str:
    """The reading that fired it, with its age: "85.00 % (0.12 s old)"; "-" when it had none."""
    age = alert["reading_age_s"]
    return (alert["reading"] or "-") + (f" ({age:.2f} s old)" if age is not None else "")

"""`ros2 topic bw` (ros2topic/verb/bw.py, humble and jazzy alike): the bytes a topic carries per
second; astiop prints its first two reports, a second apart."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from astiop.ros2.verbs.arguments import positive_int
from astiop.ros2.verbs.base import SAMPLE, Output, Verb

if TYPE_CHECKING:
    from astiop.ros2.verbs.checks import Checked
    from astiop.ros2.verbs.transport import Transport


REPORTS = 2
ROS2_WINDOW = 100  # messages, bw.py's DEFAULT_WINDOW_SIZE


def arguments(p, distro: str) -> None:
    p.add_argument("topic_name", metavar="topic")
    p.add_argument(
        "--window", "-w", dest="window_size", type=positive_int, default=ROS2_WINDOW,
        metavar="WINDOW",
    )  # fmt: skip
    p.add_argument("--spin-time", type=float)  # ros2cli/node/direct.py
    p.add_argument("-s", "--use-sim-time", action="store_true")


def check(cmd, catalog):
    from astiop.ros2.verbs.checks import checked_topic

    return checked_topic(cmd, catalog)


def reports(arrivals: list[tuple[float, int]], window: int) -> list[tuple[float, list[int]]]:
    """bw.py's prints, a second apart from the first message: (bytes per second, the sizes of
    the last `window` messages), once two have come."""
    out: list[tuple[float, list[int]]] = []
    if not arrivals:
        return out
    at = arrivals[0][0] + 1.0
    while at <= arrivals[-1][0]:
        seen = [a for a in arrivals if a[0] <= at][-window:]
        if len(seen) >= 2 and at > seen[0][0]:
            out.append((sum(s for _, s in seen) / (at - seen[0][0]), [s for _, s in seen]))
        at += 1.0
    return out


def _units(bytes_per_s: float):
    if bytes_per_s < 1000:
        return lambda n: f"{n:.0f} B"
    if bytes_per_s < 1000000:
        return lambda n: f"{n / 1000:.2f} KB"
    return lambda n: f"{n / 1000 / 1000:.2f} MB"


def report_text(bytes_per_s: float, sizes: list[int]) -> str:
    """One report as bw.py prints it, in the unit of the rate (B, KB or MB)."""
    unit = _units(bytes_per_s)
    mean = sum(sizes) / len(sizes)
    return (
        f"{unit(bytes_per_s)}/s from {len(sizes)} messages\n\tMessage size mean: "
        f"{unit(mean)} min: {unit(min(sizes))} max: {unit(max(sizes))}"
    )


def run(t: Transport, c: Checked, timeout: float) -> Output:
    name, window = c.named, c.parsed.options.get("window", ROS2_WINDOW)
    arrivals = t.samples(
        name, c.interface, lambda got: len(reports(got, window)) >= REPORTS, timeout
    )
    found = reports(arrivals, window)[:REPORTS]
    if not found:
        raise VERB.nothing_came(name, timeout)
    lines = [f"Subscribed to [{name}]"]
    lines += [report_text(bytes_per_s, sizes) for bytes_per_s, sizes in found]
    text = "\n".join(lines) + "\n"
    return text, read(text)


def enough(out: str) -> bool:
    return out.count(" messages\n") >= REPORTS


SCALE = {"B": 1, "KB": 1000, "MB": 1000 * 1000}


def read(out: str) -> dict | None:
    found = re.findall(
        r"([0-9.]+) (B|KB|MB)/s from (\d+) messages\n\tMessage size mean: ([0-9.]+) (B|KB|MB)", out
    )
    if not found:
        return None
    rate, unit, n, mean, mean_unit = found[-1]
    return {
        "bytes_per_s": float(rate) * SCALE[unit],
        "messages": int(n),
        "mean_bytes": float(mean) * SCALE[mean_unit],
        "reports": len(found),
    }


VERB = Verb(
    ("topic", "bw"),
    arguments,
    run,
    check,
    runs_as=SAMPLE,
    example="ros2 topic bw /scan",
    options={"window_size": "window"},
    measures=True,
    output_complete=enough,
    parse_output=read,
    when_silent="no bandwidth",
)

"""What a ros2 verb is to astiop: its arguments as ros2cli declares them, the checks against the
robot's catalog, and how it runs in process over a transport. Stdlib only: the emulated `ros2`
builds its parser from these at every call."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

VerbKey = tuple[str, str]
Output = tuple[str, Any]  # what ros2 prints, and the values astiop reads from it

# How a verb's work is done: the CLI transport runs `ros2` and reads its output by it.
QUERY = "query"  # asks the graph or the robot once and prints
TAKE = "take"  # takes one message (echo)
SAMPLE = "sample"  # follows a topic's arrivals for a while (hz, bw): ros2 runs until stopped
PUBLISH = "publish"
CALL = "call"
GOAL = "goal"


class BackendError(Exception):
    """The command was valid but running it failed (timeout, no message, process error)."""


def _valid(cmd: Any, catalog: Any) -> Any:
    from astiop.ros2.verbs.checks import Checked  # noqa: PLC0415 - checks loads the catalog

    return Checked(cmd.text, cmd, True)


@dataclass(frozen=True)
class Verb:
    key: VerbKey
    arguments: Callable[[Any, str], None]  # (argparse subparser, distro): as ros2cli declares it
    run: Callable[[Any, Any, float], Output]  # (Transport, Checked, timeout): in process
    check: Callable[[Any, Any], Any] = _valid  # (Ros2Command, Catalog) -> Checked
    runs_as: str = QUERY  # how the CLI transport runs it: QUERY, TAKE, SAMPLE, ...
    example: str = ""  # shown with a parse error
    options: Mapping[str, str] = field(default_factory=dict)  # argparse dest -> astiop's option
    values_from: str = ""  # the argparse dest holding YAML values (pub, call, send_goal)
    normalize: Callable[[dict, dict], None] | None = None  # (argparse namespace, options)
    measures: bool = False  # what it prints the robot measured now (provenance)
    duration: Callable[[Any], float] | None = None  # (Ros2Command) -> s it runs by its arguments
    # a SAMPLE verb's output read as ros2 prints it: enough of it yet, and its values
    output_complete: Callable[[str], bool] | None = None
    parse_output: Callable[[str], Any] | None = None
    when_silent: str = ""  # a SAMPLE verb's words when nothing came: "no rate"

    @property
    def name(self) -> str:
        return " ".join(self.key)

    def nothing_came(self, topic: str, timeout: float) -> BackendError:
        return BackendError(
            f"{topic} is not being published ({self.when_silent} within {timeout:g} s)"
        )

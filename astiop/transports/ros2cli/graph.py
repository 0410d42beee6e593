"""The robot's graph as `ros2 ... list` prints it, described with astiop's catalog where the
names and types match (an unknown service is treated as actuating)."""

from __future__ import annotations

import re
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

from astiop.ros2.catalog import Catalog
from astiop.ros2.profile import ProfileSpec
from astiop.transports.base import BackendError
from astiop.transports.live_catalog import VERBS, describe_graph

_LISTED = re.compile(r"^(?P<name>/\S*)\s+\[(?P<type>[^\]]+)\]\s*$")
_PARAM_LINE = re.compile(r"^  (?P<name>\S+)(?: \(type: (?P<type>[^)]+)\))?\s*$")


class GraphReader:
    def __init__(self, run: Callable, timeout_s: float, fixed: ProfileSpec | None = None):
        self.run = run  # (argv, timeout) -> ros2_process.Run
        self.timeout_s = timeout_s
        self.fixed = fixed  # what the operator fixed of the robot's profile

    def read(self) -> Catalog:
        """The live graph, described with our catalog where names match. A daemon that was
        already running has discovered the graph: one read. A daemon just started is still
        discovering: read until two reads agree."""
        started = self.run(["daemon", "start"], self.timeout_s)  # a failure shows in the lists
        settled = "already running" in started.out  # ros2cli/verb/daemon/start.py
        previous = None
        for _ in range(1 if settled else 3):
            lists = self.lists()
            if lists == previous:
                break
            previous = lists
        return self.describe(lists)

    def lists(self) -> dict[str, list[tuple[str, str]]]:
        with ThreadPoolExecutor(len(VERBS)) as pool:  # each call pays ros2's start-up
            return dict(zip(VERBS, pool.map(self._listed, VERBS)))

    def _listed(self, verb: str) -> list[tuple[str, str]]:
        if verb == "param":
            return self._listed_params()
        if verb == "node":
            out = self.run(["node", "list"], self.timeout_s)
            return sorted((n.strip(), "") for n in out.out.splitlines() if n.startswith("/"))
        out = self.run([verb, "list", "-t"], self.timeout_s)
        if out.returncode != 0:
            why = out.err.strip()[:200] or ("timed out" if out.stopped else "failed")
            raise BackendError(f"ros2 {verb} list: {why}")
        pairs = []
        for line in out.out.splitlines():
            m = _LISTED.match(line.strip())
            if m:
                pairs.append((m["name"], m["type"].split(",")[0].strip()))
        return sorted(pairs)

    def _listed_params(self) -> list[tuple[str, str]]:
        """("/node name", "double") per parameter: `ros2 param list --param-type` prints
        "/node:" then "  name (type: double)" (ros2param/verb/list.py, humble and jazzy)."""
        out = self.run(["param", "list", "--param-type"], self.timeout_s)
        if out.returncode != 0:
            return []  # parameters are optional: the rest of the graph still stands
        pairs, node = [], None
        for line in out.out.splitlines():
            if line.startswith("/") and line.rstrip().endswith(":"):
                node = line.strip()[:-1]
            elif node and (m := _PARAM_LINE.match(line)):
                pairs.append((f"{node} {m['name']}", m["type"] or ""))
        return sorted(pairs)

    def describe(self, lists: dict[str, list[tuple[str, str]]]) -> Catalog:
        return describe_graph(lists, self.fixed)

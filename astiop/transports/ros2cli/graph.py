"""The robot's graph as `ros2 ... list` prints it, described with astiop's catalog where the
names and types match (an unknown service is treated as actuating).

Services and actions are those their servers offer, as the rclpy transport reads them
(rclpy/graph.py): `ros2 service list` and `ros2 action list` name one by its clients too (rmw
lists both), and a client (another console's kept /stop client) is not a service the robot has.
What each node serves is what `ros2 node info` prints under "Service Servers" and "Action
Servers" (ros2node/verb/info.py, humble and jazzy): read again only when a list changed."""

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
_SECTION = re.compile(r"^  (?P<section>[A-Z][A-Za-z ]+):\s*$")
_ENTRY = re.compile(r"^    (?P<name>/\S*): ")
SERVING = {"Service Servers": "service", "Action Servers": "action"}
NODE_INFO_AT_ONCE = 4  # `ros2 node info` processes at a time (each pays ros2's start-up)


class GraphReader:
    def __init__(self, run: Callable, timeout_s: float, fixed: ProfileSpec | None = None):
        self.run = run  # (argv, timeout) -> ros2_process.Run
        self.timeout_s = timeout_s
        self.fixed = fixed  # what the operator fixed of the robot's profile
        self._served_for: tuple | None = None  # the lists `_served` was read for
        self._served: dict[str, set[str]] | None = None  # "service"/"action" -> names served

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
            lists = dict(zip(VERBS, pool.map(self._listed, VERBS)))
        return self._served_only(lists)

    def _served_only(self, lists: dict[str, list[tuple[str, str]]]):
        """The lists with each service and action kept only where a node serves it; as listed
        when no node's info could be read (the graph still stands, as ros2 lists it)."""
        key = tuple(tuple(lists[v]) for v in ("node", "service", "action"))
        if key != self._served_for:
            self._served, whole = self._read_served([n for n, _ in lists["node"]])
            self._served_for = key if whole else None  # a node not read: read again next time
        served = self._served
        if served is None:
            return lists
        return {
            **lists,
            **{v: [p for p in lists[v] if p[0] in served[v]] for v in ("service", "action")},
        }

    def _read_served(self, nodes: list[str]) -> tuple[dict[str, set[str]] | None, bool]:
        """What the nodes serve (None: none could be read), and whether every node was read."""
        if not nodes:
            return None, True
        with ThreadPoolExecutor(min(NODE_INFO_AT_ONCE, len(nodes))) as pool:
            infos = list(pool.map(self._node_info, nodes))
        read = [i for i in infos if i is not None]
        if not read:
            return None, False
        served = {v: set().union(*(i[v] for i in read)) for v in SERVING.values()}
        return served, len(read) == len(infos)

    def _node_info(self, node: str) -> dict[str, set[str]] | None:
        """What `node` serves, from `ros2 node info`; None if it could not be read (it left)."""
        out = self.run(["node", "info", node], self.timeout_s)
        if out.returncode != 0:
            return None
        served: dict[str, set[str]] = {v: set() for v in SERVING.values()}
        section = None
        for line in out.out.splitlines():
            if m := _SECTION.match(line):
                section = SERVING.get(m["section"])
            elif section and (m := _ENTRY.match(line)):
                served[section].add(m["name"])
        return served

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

"""The robot's graph as `ros2 ... list` prints it, described with astiop's catalog where the
names and types match (an unknown service is treated as actuating)."""

from __future__ import annotations

import re
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

from astiop.robot.backend import BackendError
from astiop.ros2.catalog import (
    ActionSpec,
    Catalog,
    ParamSpec,
    ServiceSpec,
    TopicSpec,
    astibot_catalog,
)
from astiop.ros2.render import STAMPED

_LISTED = re.compile(r"^(?P<name>/\S*)\s+\[(?P<type>[^\]]+)\]\s*$")
_PARAM_LINE = re.compile(r"^  (?P<name>\S+)(?: \(type: (?P<type>[^)]+)\))?\s*$")


def _params(known: Catalog, listed: list[tuple[str, str]]) -> dict[tuple[str, str], ParamSpec]:
    """The robot's parameters: astiop's own entry where it has one (limits, writable), else
    read-only with the type the robot gave. Before the robot lists any, astiop's table."""
    if not listed:
        return dict(known.params)
    params = {}
    for key, typ in listed:
        node, name = key.split(" ", 1)
        spec = known.params.get((node, name))
        params[(node, name)] = (
            replace(spec, type=typ) if spec else ParamSpec(node, name, None, type=typ)
        )
    return params


class GraphReader:
    def __init__(self, run: Callable, timeout_s: float):
        self.run = run  # (argv, timeout) -> ros2_process.Run
        self.timeout_s = timeout_s

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
        verbs = ("topic", "service", "action", "node", "param")
        with ThreadPoolExecutor(len(verbs)) as pool:  # each call pays ros2's start-up
            return dict(zip(verbs, pool.map(self._listed, verbs)))

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
        known = astibot_catalog()
        nodes = tuple(n for n, _ in lists["node"]) or known.nodes
        cat = Catalog(nodes=nodes, params=_params(known, lists.get("param", [])))
        for name, typ in lists["topic"]:
            spec = known.topics.get(name)
            if name == "/cmd_vel" and spec and typ == STAMPED:  # Jazzy's diff_drive_controller
                spec = replace(spec, type=typ)
            cat.topics[name] = spec if spec and spec.type == typ else TopicSpec(name, typ, 0, "?")
        for name, typ in lists["service"]:
            spec = known.services.get(name)
            # an unknown service is treated as actuating: it needs confirmation
            cat.services[name] = (
                spec if spec and spec.type == typ else ServiceSpec(name, typ, "?", True)
            )
        for name, typ in lists["action"]:
            spec = known.actions.get(name)
            cat.actions[name] = spec if spec and spec.type == typ else ActionSpec(name, typ, "?")
        return cat

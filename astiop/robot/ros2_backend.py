"""The real robot: the same checked commands, run by the `ros2` executable (never a shell)."""

from __future__ import annotations

import re
import shutil
import subprocess
from typing import Any

import yaml

from astiop.robot.catalog import ActionSpec, Catalog, ServiceSpec, TopicSpec, astibot_catalog
from astiop.robot.output import BackendError
from astiop.robot.validation import Checked

_LISTED = re.compile(r"^(?P<name>/\S*)\s+\[(?P<type>[^\]]+)\]\s*$")
_FIELD = re.compile(r"(\w+)=('(?:[^'\\]|\\.)*'|\"(?:[^\"\\]|\\.)*\"|[^,()]+)")


def parse_response(text: str) -> dict[str, Any]:
    """Fields of the `response:` line of `ros2 service call`, flat and best effort."""
    _, _, tail = text.partition("response:")
    values: dict[str, Any] = {}
    for key, raw in _FIELD.findall(tail):
        raw = raw.strip()
        if raw in ("True", "False"):
            values[key] = raw == "True"
        elif raw[:1] in ("'", '"'):
            values[key] = raw[1:-1]
        else:
            try:
                values[key] = float(raw) if "." in raw else int(raw)
            except ValueError:
                values[key] = raw
    return values


class Ros2Backend:
    name = "ros2"

    def __init__(self, executable: str = "ros2", timeout_s: float = 10.0):
        path = shutil.which(executable)
        if path is None:
            raise BackendError(
                f"'{executable}' was not found on PATH: source your ROS 2 setup "
                "(e.g. /opt/ros/humble/setup.bash) or use --robot sim"
            )
        self.executable = path
        self.timeout_s = timeout_s
        self._e_stopped = False
        self.catalog = self.read_catalog()

    def _run(self, argv: list[str], timeout: float) -> subprocess.CompletedProcess:
        try:
            return subprocess.run(
                [self.executable, *argv],
                capture_output=True,
                text=True,
                timeout=timeout,
                stdin=subprocess.DEVNULL,
            )
        except subprocess.TimeoutExpired:
            raise BackendError(f"ros2 {' '.join(argv[:3])} timed out after {timeout:g} s") from None
        except OSError as exc:
            raise BackendError(f"cannot run {self.executable}: {exc}") from None

    def _listed(self, verb: str) -> list[tuple[str, str]]:
        out = self._run([verb, "list", "-t"], self.timeout_s)
        if out.returncode != 0:
            raise BackendError(f"ros2 {verb} list failed: {out.stderr.strip()[:200]}")
        pairs = []
        for line in out.stdout.splitlines():
            m = _LISTED.match(line.strip())
            if m:
                pairs.append((m["name"], m["type"].split(",")[0].strip()))
        return pairs

    def read_catalog(self) -> Catalog:
        """The live graph, described with our catalog where names match."""
        known = astibot_catalog()
        cat = Catalog(nodes=known.nodes, params=known.params)
        for name, typ in self._listed("topic"):
            spec = known.topics.get(name)
            cat.topics[name] = spec if spec and spec.type == typ else TopicSpec(name, typ, 0, "?")
        for name, typ in self._listed("service"):
            spec = known.services.get(name)
            # an unknown service is treated as actuating: it needs confirmation
            cat.services[name] = (
                spec if spec and spec.type == typ else ServiceSpec(name, typ, "?", True)
            )
        for name, typ in self._listed("action"):
            spec = known.actions.get(name)
            cat.actions[name] = spec if spec and spec.type == typ else ActionSpec(name, typ, "?")
        return cat

    @property
    def e_stopped(self) -> bool:
        return self._e_stopped

    def estop(self) -> None:
        self._e_stopped = True
        zero = "{linear: {x: 0.0, y: 0.0, z: 0.0}, angular: {x: 0.0, y: 0.0, z: 0.0}}"
        self._run(["service", "call", "/stop", "std_srvs/srv/Trigger"], self.timeout_s)
        self._run(
            ["topic", "pub", "--once", "/cmd_vel", "geometry_msgs/msg/Twist", zero], self.timeout_s
        )

    def release_estop(self) -> None:
        self._e_stopped = False

    def execute(self, checked: Checked, timeout: float) -> tuple[str, Any]:
        cmd = checked.command
        argv = list(cmd.argv)
        if cmd.key == ("topic", "echo") and "once" not in cmd.flags:
            argv.append("--once")
        if cmd.key == ("topic", "pub") and cmd.name == "/cmd_vel":
            argv = self._with_clamped_values(argv, checked)
        out = self._run(argv, timeout)
        text = out.stdout + (out.stderr if out.returncode else "")
        if out.returncode != 0:
            raise BackendError(f"ros2 exited with {out.returncode}: {out.stderr.strip()[:300]}")
        return text, self._values(checked, out.stdout)

    @staticmethod
    def _with_clamped_values(argv: list[str], checked: Checked) -> list[str]:
        # the message safety reviewed (clamped) is what goes out, not the text as typed
        values = yaml.safe_dump(checked.message, default_flow_style=True, width=1000).strip()
        positional = [
            i
            for i, a in enumerate(argv)
            if i >= 2
            and not a.startswith("-")
            and argv[i - 1]
            not in (
                "-r",
                "--rate",
                "-t",
                "--times",
                "-p",
                "--print",
                "-w",
                "--wait-matching-subscriptions",
            )
        ]
        if len(positional) >= 3:
            argv[positional[2]] = values
        else:
            argv.append(values)
        return argv

    @staticmethod
    def _values(checked: Checked, stdout: str) -> Any:
        key = checked.command.key
        if key == ("topic", "echo"):
            try:
                return yaml.safe_load(stdout.split("\n---", 1)[0])
            except yaml.YAMLError:
                return None
        if key == ("service", "call"):
            return parse_response(stdout)
        if key == ("action", "send_goal"):
            m = re.search(r"Goal finished with status: (\w+)", stdout)
            return {"accepted": "Goal accepted" in stdout, "status": m[1] if m else None}
        return None

"""`astiop mcp` driven by the SDK's own client, over stdio and streamable HTTP, on the simulator.

A thread that beats the console heartbeat and answers approvals stands in for the console."""

from __future__ import annotations

import json
import math
import os
import socket
import sqlite3
import subprocess
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path

import httpx
import pytest
from mcp import Client, StdioServerParameters
from mcp.server.mcpserver.exceptions import ToolError
from mcp.types import Implementation

from astiop.config import load_settings
from astiop.mcp.approval import NO_CONSOLE, Policy
from astiop.mcp.server import AstiopMCP
from astiop.mcp.tools import CALL, TOOL_CLASSES, Call, Refused, RobotTools
from astiop.robot.estop_latch import ESTOP_REASON
from astiop.robot.factory import make_safety, make_sim_gateway
from astiop.robot.gateway import RobotGateway
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend

ENV = {**os.environ, "ASTIOP_SIM__SPEED": "20", "ASTIOP_LLM__THREADS": "1"}
ME = Implementation(name="pytest", version="1")


def stdio(db, *flags: str) -> Client:
    args = ["-m", "astiop", "--db", str(db), "mcp", *flags]
    return Client(StdioServerParameters(command=sys.executable, args=args, env=ENV), client_info=ME)


async def call(client: Client, name: str, args: dict | None = None) -> tuple[bool, str]:
    result = await client.call_tool(name, args or {})
    return result.is_error, "\n".join(c.text for c in result.content)


def unclassified(tools) -> list[str]:
    """Registered tools with no class in the one table, or a class it does not say."""
    return [
        t.name
        for t in tools
        if TOOL_CLASSES.get(t.name) not in ("read", "actuate")
        or (t.meta or {}).get("astiop/class") != TOOL_CLASSES[t.name]
    ]


# -- the table --------------------------------------------------------------------------------
async def test_every_tool_has_a_class_and_read_only_registers_no_actuation(store):
    gateway = make_sim_gateway(load_settings({}), store)
    robot = RobotTools(gateway, store, policy=None)
    full = await AstiopMCP(robot).list_tools()
    assert {t.name for t in full} == set(TOOL_CLASSES)
    assert unclassified(full) == []
    reads = await AstiopMCP(robot, read_only=True).list_tools()
    assert {t.name for t in reads} == {n for n, c in TOOL_CLASSES.items() if c == "read"}
    assert all(t.annotations.read_only_hint for t in reads)
    server = AstiopMCP(robot)
    server.add_tool(lambda: "x", name="sneaky", description="no class")
    assert unclassified(await server.list_tools()) == ["sneaky"]


# -- ros2_query runs the review it made --------------------------------------------------------
DOCK = "ros2 service call /dock std_srvs/srv/Trigger"


class DockComesUp(SimBackend):
    """A robot whose graph is read as a live one's is (refresh): the node serving /dock comes up
    just after the first read, so a second review sees an actuating service the first did not."""

    refresh_every_s = 0.0

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.whole = self.catalog
        services = {n: s for n, s in self.whole.services.items() if n != "/dock"}
        self.catalog = replace(self.whole, services=services)
        self.reads = 0

    def refresh(self) -> bool:
        self.reads += 1
        self.refreshed_at = time.monotonic()
        if self.reads >= 2:
            self.catalog = self.whole
        return True


def test_ros2_query_runs_its_own_review_so_a_service_that_appears_meanwhile_never_runs(store):
    """With confirm_actuation off, a second review that found /dock would have docked the robot
    from a read-only tool; the one review says there is no /dock, and nothing is sent."""
    settings = load_settings({"robot": {"confirm_actuation": False}})
    backend = DockComesUp(Simulator(seed=0), store)
    gateway = RobotGateway(backend, make_safety(settings, store), store=store)
    robot = RobotTools(gateway, store, Policy())
    call = Call("pytest", "ros2_query", store.start_interaction(model="m", mode="mcp", prompt="q"))
    token = CALL.set(call)
    try:
        with pytest.raises(Refused, match="^there is no service /dock"):
            robot.ros2_query(DOCK)
    finally:
        CALL.reset(token)
    assert backend.sim.goal is None  # the robot was not sent to its dock
    with store.db.conn as conn:
        rows = conn.execute(
            "SELECT command, executed FROM commands WHERE interaction_id = ?",
            [call.interaction_id],
        ).fetchall()
    assert rows == [(DOCK, 0)]
    # the scenario is real: the service is there now, and acts on the robot
    assert gateway.review(DOCK).checked.kind == "actuate"
    with pytest.raises(Refused, match="acts on the robot: use ros2_command"):
        robot.ros2_query(DOCK)


# -- the audit trail: a store that cannot write still serves, and says so -------------------
def refuse_inserts(db, table: str) -> None:
    """A real SQLite failure on every write to `table`, as a full disk or a broken file gives."""
    with sqlite3.connect(db) as conn:
        conn.execute(
            f"CREATE TRIGGER refuse_{table} BEFORE INSERT ON {table} "
            "BEGIN SELECT RAISE(ABORT, 'disk I/O error (test)'); END"
        )


async def test_a_command_the_store_cannot_record_is_said_not_swallowed(store, capsys):
    refuse_inserts(store.path, "commands")
    server = AstiopMCP(RobotTools(make_sim_gateway(load_settings({}), store), store, Policy()))
    for _ in range(2):
        result = await server.call_tool("read_topic", {"topic": "/battery_status"})
        texts = [c.text for c in result.content]
        assert not result.is_error and "percentage:" in texts[0]
        assert texts[1].startswith("note: not in astiop's audit trail: the command ")
        assert "disk I/O error (test)" in texts[1] and "\n" not in texts[1]
    # refused calls say it in their one line too
    with pytest.raises(ToolError, match=r"^there is no topic /nope.*; note: not in astiop's"):
        await server.call_tool("read_topic", {"topic": "/nope"})
    said = capsys.readouterr().err.splitlines()
    assert len(said) == 1  # the operator reads it once, not once per call
    assert said[0].startswith("astiop mcp: the audit trail could not record the command ")
    with store.db.conn as conn:
        calls = conn.execute("SELECT status FROM interactions ORDER BY id").fetchall()
    assert calls == [("done",), ("done",), ("error",)]  # the calls themselves are kept


async def test_a_call_the_store_cannot_record_is_still_served_and_says_so(store, capsys):
    refuse_inserts(store.path, "interactions")
    server = AstiopMCP(RobotTools(make_sim_gateway(load_settings({}), store), store, Policy()))
    result = await server.call_tool("robot_state", {})
    assert not result.is_error and json.loads(result.content[0].text)["robot"] == "sim"
    assert result.content[1].text.startswith(
        "note: not in astiop's audit trail: the call was not recorded: "
    )
    assert "disk I/O error (test)" in capsys.readouterr().err


# -- stdio: reads, refusals, hostile clients, the record ------------------------------------
HOSTILE = [
    ("move", {"vx": "abc"}),
    ("move", {"vx": "inf", "seconds": 1}),
    ("move", {"vx": float("nan"), "seconds": 1}),
    ("move", {"vx": 0.2, "seconds": 100}),
    ("go_to_pose", {"x": "nan", "y": 0, "theta_deg": 0}),
    ("go_to_pose", {"x": 1e308, "y": 1, "theta_deg": 0}),
    ("go_to_location", {}),
    ("go_to_location", {"name": ["shipping"]}),
    ("go_to_location", {"name": "'; DROP TABLE locations; --"}),
    ("go_to_location", {"name": "x" * 200_000}),
    ("read_topic", {"topic": "/odom --once; rm -rf /"}),
    ("read_topic", {"topic": "/no_such_topic"}),
    ("ros2_command", {"command": "rm -rf /"}),
    ("ros2_command", {"command": "ros2 " + "a" * 10_000}),
    ("ros2_command", {"command": "ros2 topic pub /cmd_vel geometry_msgs/msg/Twist \x1b[2J"}),
    ("ros2_query", {"command": "ros2 service call /dock std_srvs/srv/Trigger"}),
    ("no_such_tool", {"x": 1}),
]


@pytest.mark.slow
async def test_stdio_reads_refusals_and_hostile_arguments(tmp_path):
    db = tmp_path / "mcp.db"
    async with stdio(db) as client:
        tools = (await client.list_tools()).tools
        assert unclassified(tools) == [] and {t.name for t in tools} == set(TOOL_CLASSES)

        error, text = await call(client, "robot_state")
        state = json.loads(text)
        assert not error and state["robot"] == "sim"
        for part in ("pose", "battery", "status", "faults"):
            assert 0 <= state[part]["age_s"] < 5, part
        error, text = await call(client, "read_topic", {"topic": "/battery_status"})
        assert not error and "percentage:" in text
        error, text = await call(client, "list_locations")
        assert not error and "shipping" in text
        catalog = await client.read_resource("astiop://catalog")
        assert "/goto_position" in catalog.contents[0].text
        interfaces = await client.read_resource("astiop://interfaces")
        assert "float64 theta" in interfaces.contents[0].text

        # no console open: refused with the way out
        assert await call(client, "go_to_location", {"name": "shipping"}) == (True, NO_CONSOLE)

        for name, args in HOSTILE:
            error, text = await call(client, name, args)
            assert error and text and "\n" not in text and len(text) <= 500, (name, text)

        # a flood: every call answered (a result or one line), and the server still serves
        import anyio

        answers: list[tuple[bool, str]] = []

        async def one() -> None:
            answers.append(await call(client, "robot_state"))

        async with anyio.create_task_group() as tg:
            for _ in range(40):
                tg.start_soon(one)
        assert len(answers) == 40
        assert all(not e or "\n" not in t for e, t in answers)
        assert not (await call(client, "list_locations"))[0]

        # the E-STOP latched by another process: refused with that reason; stop still works
        Store(db).latch_estop("test")
        assert await call(client, "go_to_location", {"name": "shipping"}) == (True, ESTOP_REASON)
        error, text = await call(client, "stop")
        assert not error and text.startswith("stop sent")

    with Store(db).db.conn as conn:
        rows = conn.execute("SELECT model, mode, session, status FROM interactions").fetchall()
        sent = conn.execute(
            "SELECT command FROM commands WHERE source = 'mcp' AND executed = 1 "
            "AND kind = 'actuate'"
        ).fetchall()
    assert rows and all(r[:3] == ("mcp:pytest", "mcp", "mcp") for r in rows)
    assert {r[3] for r in rows} == {"done", "error"}
    assert [c for (c,) in sent] == ["ros2 service call /stop std_srvs/srv/Trigger"]


@pytest.mark.slow
async def test_read_only_lists_no_actuating_tool(tmp_path):
    async with stdio(tmp_path / "mcp.db", "--read-only") as client:
        names = {t.name for t in (await client.list_tools()).tools}
        assert names == {n for n, c in TOOL_CLASSES.items() if c == "read"}
        error, text = await call(client, "go_to_location", {"name": "shipping"})
        assert error and "Unknown tool" in text


@pytest.mark.slow
async def test_approve_actuation_goes_to_a_location_on_the_sim(tmp_path):
    async with stdio(tmp_path / "mcp.db", "--approve-actuation") as client:
        error, text = await call(client, "go_to_location", {"name": "inspection_zone_a"})
        assert not error and text.startswith("goal accepted: inspection_zone_a"), text
        assert "arrived" not in text
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            goal = json.loads((await call(client, "robot_state"))[1])["last_goal"]
            if goal["outcome"] != "still going":
                break
            time.sleep(0.3)
        assert goal["outcome"].startswith("arrived: inspection_zone_a"), goal


class Console(threading.Thread):
    """Stands in for an open console: beats its heartbeat and answers each request in turn
    (None: leaves it unanswered)."""

    def __init__(self, db, answers: list[bool | None]):
        super().__init__(daemon=True)
        self.db, self.answers, self.seen = db, list(answers), []
        self.done = threading.Event()

    def run(self) -> None:
        store = Store(self.db)
        while not self.done.is_set():
            store.console_heartbeat()
            for request in store.pending_approvals():
                if request["id"] in {r["id"] for r in self.seen}:
                    continue
                self.seen.append(request)
                answer = self.answers.pop(0) if self.answers else None
                if answer is not None:
                    store.decide_approval(request["id"], answer, "test console")
            time.sleep(0.1)
        store.console_closed()


@pytest.mark.slow
async def test_a_console_approves_denies_or_lets_expire(tmp_path):
    db = tmp_path / "mcp.db"
    Store(db).close()
    console = Console(db, [True, True, False, None])
    console.start()
    try:
        async with stdio(db, "--approval-timeout", "2") as client:
            error, text = await call(client, "move", {"vx": -3.0, "seconds": 0.3})
            assert not error and "commanded vx -0.8 m/s" in text and "measured: moved" in text
            error, text = await call(client, "go_to_location", {"name": "shipping"})
            assert not error and text.startswith("goal accepted: shipping"), text
            error, text = await call(client, "go_to_pose", {"x": 10, "y": 5, "theta_deg": 90})
            assert (error, text) == (True, "denied by the operator")
            error, text = await call(client, "dock")
            assert (error, text) == (True, "no answer from the operator within 2 s")
    finally:
        console.done.set()
        console.join(5)
    first = console.seen[0]
    assert first["client"] == "pytest"
    assert first["command"].startswith("ros2 topic pub -t 3 -r 10 /cmd_vel")
    assert "x: -0.8" in first["command"]  # as it is sent: clamped
    assert "clamped" in first["detail"]
    assert console.seen[1]["command"].startswith(
        "ros2 service call /goto_position astiop_msgs/srv/GotoPosition '{name: shipping,"
    )
    statuses = [Store(db).approval(r["id"])["status"] for r in console.seen]
    assert statuses == ["approved", "approved", "denied", "expired"]


# -- HTTP -------------------------------------------------------------------------------------
def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def http_server(db, port: int, *flags: str, env: dict | None = None) -> subprocess.Popen:
    args = [sys.executable, "-m", "astiop", "--db", str(db), "mcp", "--http", *flags]
    proc = subprocess.Popen(args, env=env or ENV, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), 0.2).close()
            return proc
        except OSError:
            assert proc.poll() is None, proc.stderr.read().decode()
            time.sleep(0.1)
    proc.kill()
    raise AssertionError("the HTTP server did not start")


@pytest.mark.slow
async def test_http_loopback_serves_and_a_token_is_required_when_given(tmp_path):
    port = free_port()
    proc = http_server(tmp_path / "a.db", port, f"127.0.0.1:{port}")
    try:
        async with Client(f"http://127.0.0.1:{port}/mcp", client_info=ME) as client:
            assert unclassified((await client.list_tools()).tools) == []
            error, text = await call(client, "robot_state")
            assert not error and json.loads(text)["pose"]["age_s"] is not None
            error, text = await call(client, "go_to_location", {"name": "shipping"})
            assert (error, text) == (True, NO_CONSOLE)
    finally:
        proc.terminate()
        proc.wait(10)

    token = "s3cret-token-0123456789"
    token_file = tmp_path / "token"
    token_file.write_text(token + "\n")  # as `echo` writes it
    token_file.chmod(0o600)
    port = free_port()
    proc = http_server(
        tmp_path / "b.db", port, f"127.0.0.1:{port}", "--token-file", str(token_file)
    )
    try:
        assert token.encode() not in Path(f"/proc/{proc.pid}/cmdline").read_bytes()  # `ps`
        await needs_the_token(port, token)
    finally:
        proc.terminate()
        proc.wait(10)


async def needs_the_token(port: int, token: str) -> None:
    """Refused (401) without the token and with a wrong one; served with it."""
    import httpx2
    from mcp.client.streamable_http import streamable_http_client

    hello = {"jsonrpc": "2.0", "id": 1, "method": "ping"}
    url = f"http://127.0.0.1:{port}/mcp"
    assert httpx.post(url, json=hello).status_code == 401
    wrong = {"Authorization": f"Bearer {token}x"}
    assert httpx.post(url, json=hello, headers=wrong).status_code == 401
    headers = {"Authorization": f"Bearer {token}"}
    async with (
        httpx2.AsyncClient(headers=headers) as http,
        Client(streamable_http_client(url, http_client=http), client_info=ME) as client,
    ):
        assert not (await call(client, "list_locations"))[0]


@pytest.mark.slow
async def test_http_token_from_the_environment(tmp_path):
    token = "env-token-0123456789abcdef"
    port = free_port()
    env = {**ENV, "ASTIOP_MCP_TOKEN": token}
    proc = http_server(tmp_path / "e.db", port, f"127.0.0.1:{port}", env=env)
    try:
        assert token.encode() not in Path(f"/proc/{proc.pid}/cmdline").read_bytes()
        await needs_the_token(port, token)
    finally:
        proc.terminate()
        proc.wait(10)


def test_http_off_the_loopback_needs_a_token(tmp_path):
    args = [sys.executable, "-m", "astiop", "--db", str(tmp_path / "c.db"), "mcp"]
    out = subprocess.run(
        [*args, "--http", "0.0.0.0:9"], env=ENV, capture_output=True, text=True, timeout=30
    )
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        "astiop: --http on 0.0.0.0 (not the loopback) needs a token (--token-file F (mode 600) "
        "or ASTIOP_MCP_TOKEN): anyone who reaches it could ask the robot to move"
    ]


def refused(tmp_path, *flags: str, env: dict | None = None) -> str:
    """`astiop mcp FLAGS`'s one line, for a start that must be refused before serving."""
    args = [sys.executable, "-m", "astiop", "--db", str(tmp_path / "r.db"), "mcp", *flags]
    out = subprocess.run(args, env=env or ENV, capture_output=True, text=True, timeout=30)
    assert out.returncode == 2, out
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("astiop: "), out.stderr
    return lines[0][len("astiop: ") :]


def test_a_token_on_the_command_line_is_refused(tmp_path):
    token = "on-the-command-line-0123456789"
    why = refused(tmp_path, "--http", "127.0.0.1:9", "--token", token)
    assert why == (
        "--token would show the token to every user in `ps`: give it as --token-file F "
        "(mode 600) or ASTIOP_MCP_TOKEN"
    )
    assert token not in why


def test_a_bad_token_file_or_variable_is_refused_in_one_line(tmp_path):
    def token_file(name: str, data: bytes, mode: int = 0o600):
        path = tmp_path / name
        path.write_bytes(data)
        path.chmod(mode)
        return str(path)

    good = b"s3cret-token-0123456789\n"
    http = ("--http", "0.0.0.0:9", "--token-file")
    cases = {
        token_file("open", good, 0o644): "may be read or changed by other users (mode 0644): "
        "chmod 600",
        token_file("group", good, 0o640): "(mode 0640)",
        token_file("empty", b""): "is empty",
        token_file("newline", b"\n"): "is empty",
        token_file("short", b"0123456789\n"): "the token is 10 characters; it needs 16",
        token_file("spaced", b"s3cret token 0123456789\n"): "printable ASCII with no spaces",
        token_file("lines", good + b"another\n"): "holds more than one line",
        token_file("binary", b"\xff" * 20): "is not text",
        token_file("big", b"x" * 5000): "is larger than 4096 bytes",
        str(tmp_path / "missing"): "cannot read: No such file or directory",
        str(tmp_path): "is a folder, not a file",
    }
    for path, reason in cases.items():
        why = refused(tmp_path, *http, path)
        assert why.startswith(f"--token-file {path}") and reason in why, (path, why)
        assert "s3cret" not in why
    short = {**ENV, "ASTIOP_MCP_TOKEN": "s3cret"}
    why = refused(tmp_path, "--http", "0.0.0.0:9", env=short)
    assert why == "ASTIOP_MCP_TOKEN: the token is 6 characters; it needs 16"
    why = refused(tmp_path, "--token-file", token_file("stdio", good))
    assert why == "--token-file goes with --http (stdio needs none)"


def test_an_outside_agent_may_never_release_a_held_robot(store):
    """/release is the operator's (ctrl+r, astiop estop --release): refused even with
    --approve-actuation, and the robot stays held."""
    gateway = make_sim_gateway(load_settings({}), store)
    robot = RobotTools(gateway, store, Policy(approve_actuation=True))
    call = Call(
        "pytest", "ros2_command", store.start_interaction(model="m", mode="mcp", prompt="r")
    )
    token = CALL.set(call)
    try:
        robot.ros2_command("ros2 service call /stop std_srvs/srv/Trigger")
        with pytest.raises(Refused, match="/release releases a held robot: a person does"):
            robot.ros2_command("ros2 service call /release std_srvs/srv/Trigger")
    finally:
        CALL.reset(token)
    assert gateway.state().state_word == "e_stopped"  # still held by its own stop


# -- camera_frame: the frame the robot published, as MCP image content --------------------------
class CameraNotYetUp(SimBackend):
    """A robot whose camera driver has not published its first frame yet."""

    def _last_publish(self, name: str) -> float:
        return -math.inf if "camera" in name else super()._last_publish(name)


def camera_server(store, sim: Simulator, backend=SimBackend) -> AstiopMCP:
    gateway = RobotGateway(backend(sim, store), make_safety(load_settings({}), store))
    return AstiopMCP(RobotTools(gateway, store, Policy()), read_only=True)


async def test_camera_frame_is_the_robots_frame_as_a_png_image_with_its_age(store):
    import base64
    import io

    import numpy as np
    from PIL import Image

    sim = Simulator(seed=0, start=(4.0, 3.0, math.pi - 0.3))  # the charging station on the left
    sim.step(0.5)
    async with Client(camera_server(store, sim), client_info=ME) as client:
        assert "camera_frame" in {t.name for t in (await client.list_tools()).tools}
        result = await client.call_tool("camera_frame", {})
    assert not result.is_error and [c.type for c in result.content] == ["image", "text"]
    image, text = result.content
    assert image.mime_type == "image/png"
    with Image.open(io.BytesIO(base64.b64decode(image.data, validate=True))) as img:
        assert img.format == "PNG"
        pixels = np.asarray(img.convert("RGB"))
    assert np.array_equal(pixels, sim.camera_image()[1])  # paused: the frame it published
    said = text.text
    assert said.startswith("camera frame from /camera/image_raw, 160 x 120 px, ")
    assert said.endswith(" s old (robot clock)")
    age = float(said.split("px, ")[1].split(" s old")[0])
    assert 0.0 <= age <= 0.2  # 5 Hz
    with store.db.conn as conn:  # the call is in the audit trail, its text without the image
        rows = conn.execute("SELECT prompt, answer FROM interactions").fetchall()
    assert rows == [("camera_frame {}", f"[image/png image]\n{said}")]


async def test_camera_frame_without_a_camera_or_a_frame_is_one_line(store):
    async with Client(camera_server(store, Simulator(seed=0, camera=None)), client_info=ME) as c:
        none = await c.call_tool("camera_frame", {})
    server = camera_server(store, Simulator(seed=0), CameraNotYetUp)
    async with Client(server, client_info=ME) as c:
        not_yet = await c.call_tool("camera_frame", {})  # nothing published yet
    assert [(r.is_error, [x.type for x in r.content]) for r in (none, not_yet)] == [
        (False, ["text"]),
        (False, ["text"]),
    ]
    assert none.content[0].text == "no camera"
    assert not_yet.content[0].text == "no frame yet on /camera/image_raw"

"""Hostile input and broken files, class by class: one line, exit 2, nothing written."""

from __future__ import annotations

import hashlib
import json
import os
import sqlite3
import subprocess
import sys
import threading

import pytest

from astiop.agent.models.specs import SpecError, parse_spec
from astiop.config import ConfigError, load_settings
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.validation import validate
from astiop.sim.simulator import Simulator
from astiop.store import LocationError, Store, StoreError
from astiop.transports.simulator.backend import SimBackend
from tests.cli_runner import run_cli
from tests.scripted_llm import ScriptedLLM
from tests.unit.test_agent import make_agent
from tests.unprivileged import astiop_unprivileged, reachable_folder, run_unprivileged

TWIST = "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist"


def cli(*args, db=None, process=False):
    """`astiop ARGS` through its entry point in this process, or as a process of its own."""
    argv = [*(["--db", str(db)] if db else []), *args]
    if not process:
        return run_cli(*argv)
    cmd = [sys.executable, "-m", "astiop", *argv]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)


def one_line(result, code=2):
    lines = result.stderr.strip().splitlines()
    assert result.returncode == code, result.stderr
    assert len(lines) == 1 and lines[0].startswith("astiop: "), result.stderr
    assert "Traceback" not in result.stderr + result.stdout


def digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


# -- model replies ----------------------------------------------------------------------
HOSTILE_REPLIES = [
    '{"steps": [{"tool": "drive_xy", "x": ' + "9" * 5000 + ', "y": 1}]}',
    '{"steps": [{"tool": "drive_xy", "x": ' + "9" * 400 + ', "y": 1}]}',
    "[" * 3000 + "]" * 3000,
    '{"steps": ' + '{"a": ' * 3000 + "1" + "}" * 3000 + "}",
    "x" * 100_000,
]


@pytest.mark.parametrize(
    "reply", HOSTILE_REPLIES, ids=["int5000", "int400", "deep", "deepobj", "1MB"]
)
async def test_a_hostile_plan_reply_ends_the_turn_cleanly(reply, store):
    llm = ScriptedLLM("openai")
    llm.default = reply
    try:
        agent = make_agent(llm, store, mode="tool")
        result = await agent.turn("do your thing")  # every tool offered
        assert result.error and not any(c.executed for c in result.commands)
        assert agent.gateway.backend.sim.goal is None
    finally:
        llm.close()


COMMANDS = [
    (f'{TWIST} "{{linear: {{x: {"9" * 5000}}}}}"', "limit"),
    (f'{TWIST} "{{linear: {{x: {"9" * 400}}}}}"', "finite"),
    (f'{TWIST} "' + "{a: " * 40 + "1" + "}" * 40 + '"', "deeper"),
    (f'{TWIST} "{{linear: &a {{x: 0.1}}, angular: *a}}"', "aliases"),
    (f'{TWIST} "{{linear: {{x: 1.0e+999}}}}"', "finite"),
    ("ros2 topic echo /scan\x1b]0;pwned\x07", "control"),
    ("ros2 topic echo /scan\x00", "control"),
    ("ros2 topic echo /" + "a" * 1_000_000, "limit"),
    ('ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{x: 1e308, y: 1}"', "number"),
    (
        "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist \"{linear: {x: 0.1}, 'k': ["
        + "1," * 1500
        + '1]}"',
        "",
    ),
]


@pytest.mark.parametrize("text,why", COMMANDS)
def test_a_hostile_command_is_refused_with_a_short_reason(text, why):
    checked = validate(text, astibot_catalog())
    assert not checked.valid and why in checked.reason
    assert len(checked.reason) < 400  # never the whole hostile value back


def test_a_goal_heading_of_1e308_is_refused_without_overflow():
    gateway = RobotGateway(SimBackend(Simulator(seed=0), None), SafetyPolicy())
    goal = (
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        '"{pose: {header: {frame_id: map}, pose: {position: {x: 5.0, y: 5.0}, '
        'orientation: {z: 1.0e+308, w: 1.0e+308}}}}"'
    )
    r = gateway.run(goal, confirm=lambda c: True)
    assert not r.executed and "not a unit quaternion" in r.reason  # issue 26: refused, not sent


@pytest.mark.parametrize(
    "spec,why",
    [
        ("openai:x@http://[::1", "malformed"),
        ("openai:x@http://localhost:99999/v1", "malformed"),
        ("ollama:x@ftp://host", "http(s)"),
        ("gguf:/etc/hostname", "not a GGUF file"),
        ("gguf:/nonexistent.gguf", "does not exist"),
    ],
)
def test_a_bad_model_spec_is_one_reason(spec, why):
    with pytest.raises(SpecError, match=None) as err:
        parse_spec(spec)
    assert why in str(err.value)


# -- the database ----------------------------------------------------------------------
# The user opens the store itself: what it may read and that a write is refused, said as JSON.
AS_THE_USER = """
import json, sys
from astiop.store import Store, StoreError
path = sys.argv[1]
try:
    open(path, "r+b").close()
    writes_the_file = True  # the mechanism failed: this user writes through the file's mode
except PermissionError:
    writes_the_file = False
store = Store(path)
names = [loc.name for loc in store.list_locations()]
try:
    store.add_location("x1", 5, 5)
    refused = ""
except StoreError as exc:
    refused = str(exc)
store.close()
print(json.dumps({"writes_the_file": writes_the_file, "readonly": store.readonly,
                  "names": names, "refused": refused}))
"""


@pytest.fixture
def shared_tmp():
    with reachable_folder() as folder:
        yield folder


def store_as_the_user(db) -> dict:
    r = run_unprivileged("-c", AS_THE_USER, str(db))
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def test_a_read_only_database_reads_and_refuses_writes(shared_tmp):
    """Run by a user whom file modes bind (tests/unprivileged.py): its folder is the user's to
    write, the file is not."""
    folder = shared_tmp / "open"
    folder.mkdir()
    db = folder / "ro.db"
    Store(db).close()
    before = digest(db)
    db.chmod(0o444)
    folder.chmod(0o777)
    try:
        seen = store_as_the_user(db)
        assert not seen["writes_the_file"], "the test's user writes a read-only file"
        assert seen["readonly"] and "charging_dock" in seen["names"]
        assert "read-only" in seen["refused"]
        r = astiop_unprivileged("--db", str(db), "locations", "add", "x1", "5", "5")
        one_line(r)
        assert "read-only" in r.stderr
        listed = astiop_unprivileged("--db", str(db), "locations", "list")
        assert listed.returncode == 0 and "charging_dock" in listed.stdout, listed.stderr
    finally:
        db.chmod(0o644)
        folder.chmod(0o755)
    assert digest(db) == before


def test_a_read_only_folder_still_reads(shared_tmp):
    """The file is the user's to write, its folder is not (WAL's side files live there)."""
    folder = shared_tmp / "ro"
    folder.mkdir()
    db = folder / "a.db"
    Store(db).close()
    before = digest(db)
    db.chmod(0o666)
    folder.chmod(0o555)
    try:
        seen = store_as_the_user(db)
        assert seen["readonly"] and "charging_dock" in seen["names"]
        assert "read-only" in seen["refused"]
        listed = astiop_unprivileged("--db", str(db), "locations", "list")
        assert listed.returncode == 0 and "charging_dock" in listed.stdout, listed.stderr
        one_line(astiop_unprivileged("--db", str(db), "locations", "add", "x1", "5", "5"))
        assert sorted(p.name for p in folder.iterdir()) == ["a.db"]
    finally:
        folder.chmod(0o755)
        db.chmod(0o644)
    assert digest(db) == before


@pytest.mark.parametrize("offset", [4096, "middle"])
def test_a_damaged_database_is_refused_and_left_untouched(tmp_path, offset):
    db = tmp_path / "bad.db"
    store = Store(db)
    for i in range(200):
        store.add_event("test", f"event {i} " + "x" * 200)
    store.close()
    data = bytearray(db.read_bytes())
    # a page's header, where damage is always seen (inside a page's free space it may not be)
    at = 4096 if offset == 4096 else len(data) // 2 // 4096 * 4096
    data[at : at + 512] = os.urandom(512)
    db.write_bytes(bytes(data))
    before = digest(db)
    with pytest.raises(StoreError, match="damaged|not a usable"):
        Store(db)
    one_line(cli("locations", "list", db=db))
    assert digest(db) == before


@pytest.mark.parametrize("path", ["/dev/null", "/proc/version", "/"])
def test_a_path_that_is_not_a_database_file_is_one_line(path):
    one_line(cli("locations", "list", db=path))


def test_two_writers_adding_the_same_name_get_already_exists(tmp_path):
    db = tmp_path / "race.db"
    Store(db).close()
    outcomes: list[str] = []

    def add():
        try:
            Store(db).add_location("bay_1", 5, 5)
            outcomes.append("added")
        except LocationError as exc:
            outcomes.append(str(exc))

    for _ in range(10):
        threads = [threading.Thread(target=add) for _ in range(4)]
        [t.start() for t in threads]
        [t.join() for t in threads]
        assert outcomes.count("added") == 1 and all(
            "already exists" in o for o in outcomes if o != "added"
        )
        Store(db).remove_location("bay_1")
        outcomes.clear()


def test_a_turn_left_running_by_a_dead_process_is_marked_interrupted(tmp_path):
    db = tmp_path / "i.db"
    store = Store(db)
    iid = store.start_interaction(model="m", mode="tool", prompt="hi")
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True
    )
    store.update_interaction(iid, pid=int(dead.stdout))
    mine = store.start_interaction(model="m", mode="tool", prompt="still going")
    store.close()
    again = Store(db)
    rows = dict(again.db.execute("SELECT id, status FROM interactions").fetchall())
    assert rows[iid] == "interrupted" and rows[mine] == "running"


# -- config -----------------------------------------------------------------------------
@pytest.mark.parametrize("value", ['"no"', "0", '"off"', '"false"'])
def test_the_safety_switch_takes_only_a_real_boolean(tmp_path, value):
    path = tmp_path / "c.toml"
    path.write_text(f"[robot]\nconfirm_actuation = {value}\n")
    with pytest.raises(ConfigError, match="confirm_actuation"):
        load_settings({}, env={}, path=path)


def test_the_safety_switch_from_a_variable(tmp_path):
    none = tmp_path / "none.toml"
    assert not load_settings(
        {}, env={"ASTIOP_ROBOT__CONFIRM_ACTUATION": "false"}, path=none
    ).robot.confirm_actuation
    with pytest.raises(ConfigError):
        load_settings({}, env={"ASTIOP_ROBOT__CONFIRM_ACTUATION": "off"}, path=none)
    with pytest.raises(ConfigError):
        load_settings({}, env={"ASTIOP_LLM__TIMEOUT_S": "inf"}, path=none)


def test_a_config_nested_too_deep_is_one_reason(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ConfigError):
        load_settings({}, env={}, path=path)


# -- the CLI ----------------------------------------------------------------------------
@pytest.mark.parametrize(
    "args",
    [
        ("bench", "run", "--stage", "2", "--model", "rules", "--seed", "99999999999999999999"),
        ("bench", "run", "--stage", "2", "--model", "rules", "--timeout", "nan"),
        ("bench", "run", "--stage", "2", "--model", "rules", "--timeout", "-1"),
        ("bench", "run", "--stage", "2", "--model", "rules", "--concurrency", "0"),
        ("bench", "run", "--stage", "2", "--model", "rules", "--max-tokens", "-5"),
        ("bench", "run", "--stage", "2", "--model", "rules", "--limit", "0"),
        ("sim", "bench", "--seed", "-1"),
        ("--model", "openai:x@http://[::1", "chat", "battery"),
        ("exec", "ros2 topic echo /" + "a" * 100_000),
        ("no-such-command",),
    ],
)
def test_a_bad_option_is_one_line_and_nothing_is_written(tmp_path, args):
    db = tmp_path / "o.db"
    Store(db).close()
    before = digest(db)
    # The first and the last also as the installed executable, a process of their own.
    one_line(cli(*args, db=db, process=args[0] in ("no-such-command", "--model")))
    assert digest(db) == before


def test_a_closed_stdin_is_not_a_traceback(tmp_path):
    r = subprocess.run(
        f"{sys.executable} -m astiop --db {tmp_path / 's.db'} exec "
        "'ros2 service call /dock std_srvs/srv/Trigger' <&-",
        shell=True,
        capture_output=True,
        text=True,
        timeout=60,
    )
    one_line(r)
    assert "confirmation" in r.stderr


def test_stored_text_is_shown_escaped(tmp_path):
    db = tmp_path / "e.db"
    store = Store(db)
    store.add_location("bay_1", 5, 5)
    with store.db.conn:  # as another tool might have written it
        store.db.conn.execute(
            "UPDATE locations SET description = ? WHERE name = 'bay_1'", ["\x1b]0;pwned\x07 x"]
        )
    for args in (("locations", "list"), ("locations", "show", "bay_1")):
        out = cli(*args, db=db).stdout
        assert "\x1b" not in out and "\x07" not in out and "\\x1b]0;pwned\\x07" in out
    with pytest.raises(LocationError):
        store.add_location("bay_2", 6, 6, 0.0, "\x1b[2J")


# -- safety and the record ------------------------------------------------------------
def test_named_goals_are_fenced_like_coordinates(tmp_path, store):
    with pytest.raises(LocationError, match="geofence"):
        store.add_location("edge", 0.2, 12)
    with store.db.conn:  # an older database may hold one
        store.db.conn.execute(
            "INSERT INTO locations (name, x, y, theta, description, created_at, updated_at) "
            "VALUES ('edge', 0.2, 12, 0, '', 0, 0)"
        )
    from astiop.config import load_settings as load
    from astiop.robot.factory import make_safety

    policy = make_safety(load({}, env={}, path=tmp_path / "n.toml"), store)
    gateway = RobotGateway(SimBackend(Simulator(seed=0), store), policy)
    r = gateway.run(
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: edge}"',
        confirm=lambda c: True,
    )
    assert not r.executed and "geofence" in r.reason and gateway.backend.sim.goal is None


def test_every_command_exec_runs_is_recorded_with_its_source(tmp_path):
    db = tmp_path / "r.db"
    for cmd in (
        "ros2 topic echo /battery_status --once",
        "ros2 service call /dock std_srvs/srv/Trigger",
    ):
        cli("exec", "--yes", cmd, db=db)
    cli("exec", "ros2 topic echo /nope --once", db=db)
    cli("exec", "ros2 service call /dock std_srvs/srv/Trigger", db=db)  # not confirmed
    rows = sqlite3.connect(db).execute("SELECT command, executed, source FROM commands").fetchall()
    assert [r[2] for r in rows] == ["exec"] * 3 and [r[1] for r in rows] == [1, 1, 0]
    assert "/nope" not in str(rows)  # not a command of this robot: nothing ran, nothing kept


async def test_a_server_that_answers_503_gets_the_rules_fallback(store):
    llm = ScriptedLLM("openai")
    llm.mode = "http503"
    try:
        result = await make_agent(llm, store).turn("what is the battery level?")
        assert result.answer.startswith("[rules fallback]") and result.commands[0].executed
    finally:
        llm.close()


async def test_a_reply_cut_off_mid_stream_is_kept_with_the_turn(store):
    llm = ScriptedLLM("openai")
    llm.mode = "truncated"
    llm.default = '{"commands": ["ros2 topic echo /battery_status --once"]}'
    try:
        result = await make_agent(llm, store).turn("battery?")
        raw = json.loads(
            store.db.execute(
                "SELECT raw_replies FROM interactions WHERE id = ?", [result.interaction_id]
            ).fetchone()[0]
        )
        assert any(r.endswith("[cut off]") and r.startswith('{"comm') for r in raw)
    finally:
        llm.close()


def test_a_database_astiop_may_not_write_is_opened_read_only(tmp_path, monkeypatch):
    """Once astiop decides it may not write (the tests above make it decide, as a user whom file
    modes bind), every write is refused: by astiop first, and by SQLite too."""
    import astiop.store as store_module

    db = tmp_path / "ro.db"
    Store(db).close()
    before = digest(db)
    monkeypatch.setattr(store_module, "_writable", lambda path: False)
    store = Store(db)
    assert store.readonly and [loc.name for loc in store.list_locations()]
    for write in (
        lambda: store.add_location("x1", 5, 5),
        lambda: store.add_event("k", "m"),
        lambda: store.start_interaction(model="m", mode="tool", prompt="p"),
    ):
        with pytest.raises(StoreError, match="read-only"):
            write()
    with pytest.raises(sqlite3.OperationalError, match="readonly"):
        store.db.conn.execute("DELETE FROM locations")  # SQLite itself holds the line too
    store.close()
    assert digest(db) == before

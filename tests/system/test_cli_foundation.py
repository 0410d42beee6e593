"""The CLI as an operator uses it, in process (one test runs the executable), a temporary
database."""

import asyncio
import json
import socket
import subprocess
import sys

import pytest

from tests.cli_runner import run_cli


def astiop(*args):
    return run_cli(*args)


def test_version_and_help():
    out = subprocess.run(  # the installed command, end to end
        [sys.executable, "-m", "astiop", "--version"], capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0 and out.stdout.startswith("astiop ")
    out = astiop("--help")
    for sub in ("config", "locations"):
        assert sub in out.stdout


def test_locations_round_trip(tmp_path):
    db = str(tmp_path / "t.db")
    assert (
        astiop(
            "--db",
            db,
            "locations",
            "add",
            "bay_7",
            "12.5",
            "4",
            "90",
            "--description",
            "loading bay",
        ).returncode
        == 0
    )
    shown = json.loads(astiop("--db", db, "locations", "show", "BAY_7", "--json").stdout)
    assert shown == [
        {"name": "bay_7", "x": 12.5, "y": 4.0, "theta_deg": 90.0, "description": "loading bay"}
    ]
    assert astiop("--db", db, "locations", "rename", "bay_7", "bay-8").returncode == 0
    listed = json.loads(astiop("--db", db, "locations", "list", "--json").stdout)
    assert "bay-8" in [row["name"] for row in listed] and len(listed) == 7
    assert astiop("--db", db, "locations", "remove", "bay-8").returncode == 0
    assert astiop("--db", db, "locations", "show", "bay-8").returncode == 2


def _one_line_exit_2(result):
    assert result.returncode == 2, result
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert "Traceback" not in result.stderr


def test_bad_input_exits_2_with_one_line_and_changes_nothing(tmp_path):
    db = str(tmp_path / "t.db")
    before = astiop("--db", db, "locations", "list", "--json").stdout
    _one_line_exit_2(astiop("--db", db, "locations", "add", "bad name", "1", "1"))
    _one_line_exit_2(astiop("--db", db, "locations", "add", "shipping", "1", "1"))
    _one_line_exit_2(astiop("--db", db, "locations", "add", "far", "100", "1"))
    _one_line_exit_2(astiop("--db", db, "locations", "rename", "nowhere", "x"))
    assert astiop("--db", db, "locations", "list", "--json").stdout == before


def test_random_bytes_db(tmp_path):
    path = tmp_path / "junk.db"
    path.write_bytes(b"\x13\x37" * 5000)
    _one_line_exit_2(astiop("--db", str(path), "locations", "list"))
    assert path.read_bytes() == b"\x13\x37" * 5000


def test_malformed_config(tmp_path, monkeypatch):
    cfg = tmp_path / "bad.toml"
    cfg.write_text("[llm]\nthreads = -3\n")
    monkeypatch.setenv("ASTIOP_CONFIG", str(cfg))
    result = astiop("config", "show")
    _one_line_exit_2(result)
    assert str(cfg) in result.stderr and "llm.threads" in result.stderr


def test_config_path_and_show(tmp_path, monkeypatch):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[sim]\nseed = 42\n")
    monkeypatch.setenv("ASTIOP_CONFIG", str(cfg))
    assert astiop("config", "path").stdout.strip() == str(cfg)
    assert "seed = 42" in astiop("config", "show").stdout


def test_doctor_on_a_fresh_install_and_with_a_broken_model(tmp_path):
    db = str(tmp_path / "d.db")
    out = astiop("--db", db, "doctor")
    assert out.returncode == 0 and out.stdout.rstrip().endswith("ready"), out.stdout
    for check in ("python", "packages", "settings", "database", "model (selected)", "robot"):
        assert f"  {check}" in out.stdout
    from astiop.store import SCHEMA_VERSION

    assert f"schema {SCHEMA_VERSION}/{SCHEMA_VERSION}, quick_check ok" in out.stdout
    broken = astiop("--db", db, "--model", "openai:x@http://127.0.0.1:9/v1", "doctor", "--json")
    report = json.loads(broken.stdout)
    assert broken.returncode == 1 and not report["ok"]
    failed = [c for c in report["checks"] if c["status"] == "FAIL"]
    assert [c["check"] for c in failed] == ["model (selected)"]


def dead_port() -> int:
    """A port nothing listens on: bound, then closed."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_doctor_says_which_server_is_down_and_why(tmp_path):
    db = str(tmp_path / "d.db")
    port = dead_port()
    out = astiop("--db", db, "--model", f"openai:x@http://127.0.0.1:{port}/v1", "doctor")
    line = next(ln for ln in out.stdout.splitlines() if "model (selected)" in ln)
    assert out.returncode == 1 and line.startswith("FAIL")
    assert line.endswith(f"nothing listens at 127.0.0.1:{port} (connection refused)"), line
    out = astiop("--db", db, "--model", "openai:x@http://foo.invalid:8080/v1", "doctor")
    line = next(ln for ln in out.stdout.splitlines() if "model (selected)" in ln)
    # .invalid never resolves (RFC 6761); with no resolver at all the lookup fails otherwise
    assert "no such host: foo.invalid" in line or "cannot resolve foo.invalid" in line, line


def test_doctor_says_when_a_server_does_not_answer_in_time():
    from astiop.cli.doctor import unreachable_reason

    with socket.socket() as server, socket.socket() as first:
        server.bind(("127.0.0.1", 0))
        server.listen(0)  # a backlog of one, never accepted: the next connect gets no answer
        port = server.getsockname()[1]
        first.connect(("127.0.0.1", port))
        reason = asyncio.run(unreachable_reason(f"http://127.0.0.1:{port}/v1", timeout_s=0.5))
        assert reason == f"127.0.0.1:{port} did not answer in 0.5 s"
    with socket.socket() as server:  # one that accepts: nothing to explain
        server.bind(("127.0.0.1", 0))
        server.listen(8)
        url = f"http://127.0.0.1:{server.getsockname()[1]}/v1"
        assert asyncio.run(unreachable_reason(url, timeout_s=0.5)) is None


def test_record_takes_an_optional_file(monkeypatch):
    import astiop.cli.console as console_module

    seen = []
    monkeypatch.setattr(console_module, "run_console", lambda st, record: seen.append(record))
    for args in (("--record",), ("--record", "x.mcap"), ("--model", "rules", "--record"), ()):
        assert astiop(*args).returncode == 0
    assert seen == ["", "x.mcap", "", None]  # "": the default file under the data dir


def test_chat_ends_at_once_with_its_answer_and_its_record(tmp_path):
    # the executable leaves without Python's teardown: the answer and the record are complete
    db = tmp_path / "chat.db"
    argv = ["--db", str(db), "chat", "--model", "rules", "what is the battery level?", "--json"]
    out = subprocess.run(
        [sys.executable, "-m", "astiop", *argv], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert "battery" in json.loads(out.stdout)["answer"]
    from astiop.store import Store

    store = Store(db)
    try:
        [row] = store.interactions()
        assert row["status"] == "done" and "battery" in row["answer"]
    finally:
        store.close()
    # in a process that goes on (as here), the same command returns
    again = astiop(*argv)
    assert again.returncode == 0 and "battery" in json.loads(again.stdout)["answer"]


def test_astiop_chat_starts_a_model_process_first_and_ends_it_when_unused(tmp_path, monkeypatch):
    from astiop.agent.models import model_spawn

    started = []

    def popen():
        started.append(real())
        return started[-1]

    real = model_spawn._popen
    monkeypatch.setattr(model_spawn, "_popen", popen)
    db = ("--db", str(tmp_path / "a.db"))
    assert astiop(*db, "models", "--json").returncode == 0
    assert astiop(*db, "--model", "rules", "chat", "battery?", "--json").returncode == 0
    assert started == []  # only a chat that may serve a local model starts one
    monkeypatch.setenv("ASTIOP_MODEL", "rules")  # the settings, read later, name another model
    out = astiop(*db, "chat", "battery?", "--json")
    assert out.returncode == 0, out.stderr
    [ahead] = started
    assert ahead.returncode is not None  # not wanted: ended and reaped with the command


@pytest.mark.parametrize(
    "argv, command, model",
    [
        (["chat", "where is it?"], "chat", None),
        (["--db", "chat", "models"], "models", None),  # "chat" is --db's value
        (["--model=rules", "--robot", "sim", "chat", "x"], "chat", "rules"),
        (["--record", "chat", "x"], "x", None),  # as typer reads it: a recording named chat
        (["--record", "--db", "d", "chat", "-m", "ollama:q", "x"], "chat", "ollama:q"),
        (["--version"], None, None),
    ],
)
def test_the_command_and_model_are_read_before_typer_parses_them(argv, command, model):
    import typer

    from astiop.cli import _VALUED, _command_and_model
    from astiop.cli.commands import app

    params = typer.main.get_command(app).params  # typer's own click: options known by their kind
    valued = {o for p in params if p.param_type_name == "option" and not p.is_flag for o in p.opts}
    assert valued == set(_VALUED)  # a new global option with a value is known here too
    assert _command_and_model(argv) == (command, model)

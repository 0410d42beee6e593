import json

from tests.cli_runner import run_cli


def astiop(*args):
    return run_cli(*args)


def test_exec_json_read(tmp_path):
    out = astiop(
        "--db", str(tmp_path / "t.db"), "exec", "ros2 topic echo /robot_pose --once", "--json"
    )
    data = json.loads(out.stdout)
    assert set(data) >= {"command", "valid", "reason", "kind", "executed", "output", "values"}
    assert data["valid"] and data["executed"] and data["kind"] == "read"
    assert data["values"]["x"] == 1.15 and "theta:" in data["output"]


def test_exec_rejected_exits_2_and_dry_run(tmp_path):
    db = str(tmp_path / "t.db")
    out = astiop("--db", db, "exec", "ros2 topic echo /nope")
    assert out.returncode == 2 and "no topic /nope" in out.stderr
    out = astiop(
        "--db",
        db,
        "exec",
        "--dry-run",
        "--json",
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: shipping}"',
    )
    data = json.loads(out.stdout)
    assert out.returncode == 0 and data["valid"] and data["kind"] == "actuate"
    assert data["executed"] is False


def test_exec_actuating_needs_yes(tmp_path):
    db = str(tmp_path / "t.db")
    cmd = (
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: inspection_zone_a}"'
    )
    out = astiop("--db", db, "exec", cmd)
    assert out.returncode == 2 and "--yes" in out.stderr
    out = astiop("--db", db, "exec", "--yes", "--json", cmd)
    assert out.returncode == 0 and json.loads(out.stdout)["values"]["success"] is True

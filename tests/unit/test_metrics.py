"""`--metrics`: Prometheus's text format, as a scrape reads it, from the journal and the robot;
a bearer token off the loopback; `astiop watch run --metrics` on the simulator."""

from __future__ import annotations

import httpx
import pytest
from prometheus_client.parser import text_string_to_metric_families

from astiop.metrics import AstiopCollector, MetricsServer, RobotFigures, parse_address
from astiop.transports.state import Battery, RobotState, Status
from tests.cli_runner import run_cli

TOKEN = "s3cret-token-of-twenty-chars"


def _samples(text: str) -> dict[tuple[str, tuple], float]:
    return {
        (s.name, tuple(sorted(s.labels.items()))): s.value
        for family in text_string_to_metric_families(text)
        for s in family.samples
    }


def _robot(e_stopped: bool = False) -> RobotFigures:
    status = Status("navigating", "auto", "dock", "", 0.4, e_stopped, False)
    state = RobotState(
        t=12.0,
        velocity=(0.3, 0.4, 0.0),
        battery=Battery(0.42, 25.1, -1.5, False),
        status=status,
        e_stopped=e_stopped,
    )
    return RobotFigures("astibot_2", state, e_stopped, "console (pid 7 on jetson)")


def _journal(store) -> None:
    turn = store.start_interaction(model="rules", mode="chat", prompt="battery?")
    store.update_interaction(
        turn, status="done", total_s=0.5, prompt_tokens=100, completion_tokens=20
    )
    store.add_command(turn, command="ros2 topic echo /battery", valid=1, executed=1)
    store.add_command(turn, command="ros2 topic pub /cmd_vel", valid=0, reason="unsafe")
    store.add_command(turn, command="ros2 action send_goal", valid=1, executed=0)
    store.add_command(turn, command="ros2 topic echo /odom", valid=1, executed=1)
    store.fire_alert("battery#a", robot="astibot_2", kind="battery_low", message="low")


def test_a_scrape_says_what_the_robot_and_the_journal_hold(store):
    _journal(store)
    server = MetricsServer(AstiopCollector(store, lambda: [_robot()]), "127.0.0.1", 0)
    try:
        reply = httpx.get(server.url, timeout=10)
    finally:
        server.close()
    assert reply.status_code == 200
    got = _samples(reply.text)
    robot = (("robot", "astibot_2"),)
    assert got[("astiop_robot_battery_ratio", robot)] == pytest.approx(0.42)
    assert got[("astiop_robot_battery_volts", robot)] == pytest.approx(25.1)
    assert got[("astiop_robot_speed_mps", robot)] == pytest.approx(0.5)
    assert got[("astiop_robot_state", (("robot", "astibot_2"), ("state", "navigating")))] == 1
    assert got[("astiop_robot_state", (("robot", "astibot_2"), ("state", "idle")))] == 0
    assert got[("astiop_robot_estop", robot)] == 0
    holder = (("holder", "console (pid 7 on jetson)"), ("robot", "astibot_2"))
    assert got[("astiop_robot_controlled", holder)] == 1
    assert got[("astiop_commands_total", (("verdict", "executed"),))] == 2
    assert got[("astiop_commands_total", (("verdict", "refused"),))] == 1
    assert got[("astiop_commands_total", (("verdict", "not_executed"),))] == 1
    assert got[("astiop_turns_total", (("model", "rules"), ("status", "done")))] == 1
    assert got[("astiop_turn_seconds_sum", (("model", "rules"),))] == pytest.approx(0.5)
    assert got[("astiop_model_tokens_total", (("kind", "prompt"), ("model", "rules")))] == 100
    alerts = (("kind", "battery_low"), ("robot", "astibot_2"))
    assert got[("astiop_alerts_open", alerts)] == 1
    store.acknowledge_alert(store.list_alerts()[0]["id"], "ann")
    assert ("astiop_alerts_open", alerts) not in _samples(_scrape(store))


def _scrape(store, robots=()) -> str:
    server = MetricsServer(AstiopCollector(store, lambda: robots), "127.0.0.1", 0)
    try:
        return httpx.get(server.url, timeout=10).text
    finally:
        server.close()


def test_an_unread_robot_leaves_its_readings_out_and_keeps_its_estop(store):
    gone = RobotFigures("tb3", None, True, None)
    got = _samples(_scrape(store, [gone]))
    assert got[("astiop_robot_estop", (("robot", "tb3"),))] == 1
    assert not any(name == "astiop_robot_battery_ratio" for name, _ in got)


def test_a_token_is_asked_for_when_set(store):
    server = MetricsServer(AstiopCollector(store, lambda: ()), "127.0.0.1", 0, token=TOKEN)
    try:
        assert httpx.get(server.url, timeout=10).status_code == 401
        wrong = {"Authorization": "Bearer not-the-token-at-all"}
        assert httpx.get(server.url, headers=wrong, timeout=10).status_code == 401
        right = {"Authorization": f"Bearer {TOKEN}"}
        assert httpx.get(server.url, headers=right, timeout=10).status_code == 200
    finally:
        server.close()


@pytest.mark.parametrize(
    "address, said",
    [("abc", "give HOST:PORT or PORT"), ("host:99999", "the port must be 0-65535")],
)
def test_a_bad_address_is_refused_in_one_line(address, said):
    with pytest.raises(ValueError, match=said):
        parse_address(address)
    assert parse_address("9100") == ("127.0.0.1", 9100)
    assert parse_address("[::1]:9100") == ("::1", 9100)


def test_off_the_loopback_a_token_is_needed(tmp_path):
    r = run_cli("--db", str(tmp_path / "a.db"), "watch", "run", "--metrics", "0.0.0.0:0")
    assert r.returncode != 0
    assert "not the loopback" in r.stderr and "--metrics-token-file" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_the_grafana_dashboard_reads_only_metrics_astiop_exports(store):
    import json
    import re
    from pathlib import Path

    _journal(store)
    exported = {name for name, _ in _samples(_scrape(store, [_robot()]))}
    dashboard = json.loads((Path(__file__).parents[2] / "docs/grafana-astiop.json").read_text())
    used = {
        name
        for panel in dashboard["panels"]
        for target in panel["targets"]
        for name in re.findall(r"astiop_[a-z_]+", target["expr"])
    }
    assert used and used <= exported, used - exported

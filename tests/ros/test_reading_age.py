"""Age and provenance of what the robot reported (#24 item 3): a reading older than two of its
topic's periods is said with its age, a silent topic is said as such, and what a service
accepted or astiop commanded is never said as done or measured."""

from __future__ import annotations

import time

import pytest

from astiop.agent import grounding
from astiop.agent.facts import facts_of
from astiop.agent.summaries import summarize
from astiop.config import load_settings
from astiop.robot.factory import make_robot_gateway, make_sim_gateway
from astiop.store import Store
from astiop.transports.base import Execution
from tests.ros import require_ros, until

ECHO_BATTERY = "ros2 topic echo --once /battery_status sensor_msgs/msg/BatteryState"
BATTERY = {"percentage": 0.85, "voltage": 27.12, "current": 4.4, "power_supply_status": 1}
GOTO = "ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{name: 'shipping'}\""


def reading(age_s: float | None, period_s: float | None = 1.0) -> Execution:
    ex = Execution(ECHO_BATTERY, True, executed=True, values=BATTERY)
    ex.age_s, ex.period_s = age_s, period_s
    return ex


def test_a_reading_older_than_two_periods_is_said_with_its_age():
    assert "(read 12 s ago)" in summarize(reading(12.0))
    assert "ago" not in summarize(reading(1.9))  # within two periods: current
    assert "ago" not in summarize(reading(12.0, period_s=None))  # latched: no period to miss
    assert "ago" not in summarize(reading(None))  # a robot whose clock is not known here


def test_an_answer_that_leaves_out_a_stale_readings_age_is_replaced():
    ex = reading(30.0)
    facts = facts_of("what is the battery level?", [ex])
    text, gap, _ = grounding.grounded("The battery is at 85.0 %.", facts, [ex])
    assert gap == "it leaves out how old the robot's reading is"
    assert "read 30 s ago" in grounding.factual_answer([ex])
    _, gap, _ = grounding.grounded("The battery was at 85.0 %, read 30 s ago.", facts, [ex])
    assert gap is None


def test_a_service_that_takes_a_job_on_reads_accepted_not_succeeded():
    values = {"success": True, "message": "navigating to shipping, 36.1 m along the path"}
    ex = Execution(GOTO, True, kind="actuate", executed=True, values=values, provenance="accepted")
    assert summarize(ex).endswith("accepted: navigating to shipping, 36.1 m along the path")
    facts = facts_of("go to shipping", [ex])
    kept, reason, _ = grounding.grounded(
        "The robot successfully went to shipping. The goal to shipping was accepted.", facts, [ex]
    )
    assert kept == "The goal to shipping was accepted." and reason is None
    stop = Execution("ros2 service call /stop std_srvs/srv/Trigger", True, kind="actuate",
                     executed=True, values={"success": True, "message": "stopped"})  # fmt: skip
    assert summarize(stop).endswith("succeeded: stopped")


def test_a_published_twist_reads_as_commanded_on_every_transport():
    cmd = "ros2 topic pub -t 5 -r 10 /cmd_vel geometry_msgs/msg/Twist '{angular: {z: -0.6}}'"
    sim = Execution(cmd, True, kind="actuate", executed=True,
                    values={"published": 5, "twist": {"angular": {"z": -0.6}}})  # fmt: skip
    output = "publisher: beginning loop\n" + "publishing #1: ...\n" * 5
    cli = Execution(cmd, True, kind="actuate", executed=True, output=output)  # no values
    for ex in (sim, cli):
        assert summarize(ex).endswith(
            "commanded rotation right 0.60 rad/s on /cmd_vel, sent 5 time(s)"
        )


def test_the_simulator_dates_its_readings_on_its_own_clock(store):
    gateway = make_sim_gateway(load_settings({}), store)
    ex = gateway.run(ECHO_BATTERY)
    assert ex.executed and not ex.error
    assert ex.period_s == pytest.approx(1.0 / gateway.catalog.topics["/battery_status"].rate_hz)
    assert ex.age_s is not None and ex.age_s <= ex.period_s
    assert "ago" not in summarize(ex)


@pytest.mark.ros
def test_a_stale_stamp_and_a_silent_topic_on_real_dds(tmp_path):
    """A driver republishing an old reading is said with its age; a topic that went silent is
    "no reading", never its last value as current."""
    require_ros()
    from builtin_interfaces.msg import Time
    from sensor_msgs.msg import BatteryState

    from tests.ros import ros_client

    settings = load_settings(
        {"llm": {"model": "rules"}, "robot": {"backend": "ros2", "ros2_transport": "rclpy"}},
        env={},
        path=tmp_path / "none.toml",
    )
    with ros_client("stale_battery_driver") as driver:
        pub = driver.node.create_publisher(BatteryState, "/battery_status", 10)

        def publish() -> None:  # each reading stamped 30 s before it goes out
            stamp = driver.node.get_clock().now().nanoseconds - 30 * 10**9
            msg = BatteryState(percentage=0.85, voltage=27.12, power_supply_status=1)
            msg.header.stamp = Time(sec=stamp // 10**9, nanosec=stamp % 10**9)
            pub.publish(msg)

        timer = driver.node.create_timer(0.2, publish)
        store = Store(tmp_path / "age.db")
        gateway = make_robot_gateway(settings, store)
        gateway.start()
        try:
            assert until(lambda: "/battery_status" in gateway.catalog.topics, 20)
            ex = gateway.run(ECHO_BATTERY)
            assert not ex.error, ex.error
            assert ex.age_s == pytest.approx(30.0, abs=3.0)
            assert "battery 85.0 %" in summarize(ex) and "s ago)" in summarize(ex)

            driver.node.destroy_timer(timer)  # the driver goes silent
            time.sleep(1.5)
            silent = gateway.run(ECHO_BATTERY.replace("--once", "--once --timeout 1"))
            assert silent.error == "no reading from /battery_status in 1 s"
            assert grounding.nothing_ran([silent]).startswith(
                "`ros2 topic echo --once` failed: no reading from /battery_status in 1 s"
            )
        finally:
            gateway.close()
            store.close()


def test_the_gateway_says_what_kind_of_fact_each_result_is_and_the_store_keeps_it(store):
    gateway = make_sim_gateway(load_settings({}), store)
    yes = lambda _c: True  # noqa: E731
    kinds = {
        ECHO_BATTERY: "measured",
        "ros2 topic hz /odom --window 5": "measured",
        "ros2 service call /undock std_srvs/srv/Trigger": "accepted",
        "ros2 service call /list_locations astiop_msgs/srv/ListLocations": "reported",
        "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{linear: {x: 0.1}}'": "commanded",
        "ros2 service call /stop std_srvs/srv/Trigger": "reported",
    }
    for command, kind in kinds.items():
        ex = gateway.run(command, yes)
        assert ex.executed and not ex.error, (command, ex.error)
        assert ex.provenance == kind, command
        gateway.record(ex, "test")
    rows = store.db.conn.execute("SELECT command, provenance, age_s FROM commands").fetchall()
    assert [(c, p) for c, p, _ in rows] == list(kinds.items())
    assert rows[0][2] is not None and rows[1][2] is None  # an echo is dated; hz is not

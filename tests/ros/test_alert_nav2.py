"""A Nav2 goal another client sent and then cancelled is a built-in alert on the rclpy
transport: a TurtleBot3 under Nav2 (`astiop sim node --robot turtlebot3`) over real DDS; the
goal's end is read from its NavigateToPose server's status topic."""

from __future__ import annotations

import time

import pytest

from astiop.config import load_settings
from astiop.robot.factory import make_robot_gateway
from astiop.store import Store
from astiop.watches.runner import make_evaluator
from tests.ros import require_ros, ros_client, until

pytestmark = [pytest.mark.slow, pytest.mark.ros]


def test_another_clients_cancelled_nav2_goal_is_an_alert_once(tmp_path):
    require_ros()
    from action_msgs.msg import GoalStatus
    from nav2_msgs.action import NavigateToPose
    from rclpy.action import ActionClient

    from tests.ros import tb3_node

    cfg = {"llm": {"model": "rules"}, "robot": {"backend": "ros2", "ros2_transport": "rclpy"}}
    settings = load_settings(cfg, env={}, path=tmp_path / "none.toml")
    with tb3_node(speed=4.0), ros_client("someone_else") as client:
        store = Store(tmp_path / "nav2.db")
        gateway = make_robot_gateway(settings, store)
        gateway.start()
        try:
            assert until(lambda: gateway.state().pose and gateway.state().battery, 30)
            ev = make_evaluator(gateway, store, settings)
            action = ActionClient(client.node, NavigateToPose, "/navigate_to_pose")
            assert action.wait_for_server(timeout_sec=15)
            goal = NavigateToPose.Goal()
            goal.pose.header.frame_id = "map"
            # 24 m ahead: it ends only when stopped, however loaded the machine
            goal.pose.pose.position.x, goal.pose.pose.position.y = 28.0, 4.0
            goal.pose.pose.orientation.w = 1.0
            handle = client.result(action.send_goal_async(goal))
            assert handle.accepted
            seq, fired = gateway.state().event_seq, []

            def step() -> list[dict]:
                nonlocal seq
                state, events = gateway.state(), gateway.events_since(seq)
                seq = events[-1].seq if events else seq
                fired.extend(ev.step(state, now=state.t, events=events))
                return [a for a in fired if a["kind"].startswith("goal_")]

            def running() -> bool:  # no status until the goal status topic is matched and read
                status = gateway.state().status
                return status is not None and bool(status.active_goal)

            assert until(lambda: step() == [] and running(), 30)
            client.result(handle.cancel_goal_async(), 15)
            done = client.result(handle.get_result_async(), 20)
            assert done.status == GoalStatus.STATUS_CANCELED
            assert until(step, 10), [e.message for e in gateway.events_since(0)]
            time.sleep(1.0)
            step()
            (alert,) = [a for a in fired if a["kind"].startswith("goal_")]
            assert alert["kind"] == "goal_canceled"
            assert alert["message"] == "goal cancelled by someone else: another client's goal"
        finally:
            gateway.close()
            store.close()

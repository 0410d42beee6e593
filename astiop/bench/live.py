"""Stage 2 on a live ROS 2 robot (`bench run --stage 2 --robot ros2`, e.g. against `astiop sim
node`): each case is set up by driving the robot to its start, and checked against what the
robot reported, a navigation by the robot's arrival."""

from __future__ import annotations

import asyncio
import threading
import time

from astiop.bench import stage2
from astiop.bench.case_turn import case_agent, scored
from astiop.config import Settings
from astiop.robot.gateway import RobotGateway

GOAL_WAIT_S = 600.0
CONVEYOR_WAIT_S = 10.0
_live: dict[int, RobotGateway] = {}
_lock = threading.Lock()


def live_gateway(settings: Settings, store) -> RobotGateway:
    """One gateway to the robot per run's world store, started once."""
    from astiop.robot.factory import make_robot_gateway

    with _lock:
        gw = _live.get(id(store))
        if gw is None:
            gw = make_robot_gateway(settings, store, who="bench")
            gw.start()
            _live[id(store)] = gw
        return gw


def close_live(store) -> None:
    with _lock:
        gw = _live.pop(id(store), None)
    if gw is not None:
        gw.close()


def _yes(_checked) -> bool:
    return True


def _settle(gateway: RobotGateway, timeout_s: float) -> None:
    """Until the robot reports no goal and no motion."""
    deadline = time.monotonic() + timeout_s
    time.sleep(0.6)  # a status at 2 Hz may still say idle just after a goal starts
    while time.monotonic() < deadline:
        if stage2.Truth.of_robot(gateway.state()).stopped:
            return
        time.sleep(0.2)


def set_up(gateway: RobotGateway, case, store) -> str:
    """Drive the robot to the case's start; "" or why it could not."""
    start = case.setup.get("start", "docked")
    deadline = time.monotonic() + 15.0
    while gateway.state().status is None:  # the robot's first /robot_status
        if time.monotonic() > deadline:
            return "set-up failed: the robot publishes no /robot_status"
        time.sleep(0.1)
    gateway.run("ros2 service call /stop std_srvs/srv/Trigger", confirm=_yes)
    if "/release" in gateway.catalog.services:  # a robot that latches its stop: let go of it
        gateway.run("ros2 service call /release std_srvs/srv/Trigger", confirm=_yes)
    truth = stage2.Truth.of_robot(gateway.state())
    if start == "docked":
        if truth.docked:
            return ""
        command = "ros2 service call /dock std_srvs/srv/Trigger"
    else:
        if truth.docked:
            gateway.run("ros2 service call /undock std_srvs/srv/Trigger", confirm=_yes)
            _settle(gateway, 60)
        x, y, th = stage2._pose_of(store, start)
        command = (
            "ros2 service call /goto_position astiop_msgs/srv/GotoPosition "
            f'"{{x: {x}, y: {y}, theta: {th}}}"'
        )
    r = gateway.run(command, confirm=_yes)
    if not r.executed or r.error or not (r.values or {}).get("success", False):
        return f"set-up failed: {r.reason or r.error or (r.values or {}).get('message')}"
    _settle(gateway, GOAL_WAIT_S)
    return ""


async def live_case(store, settings, config, endpoint, case, mode):
    why = stage2.live_refusal(case)
    if why:
        return "skipped", {"total_s": 0.0, "skipped": why}, ""
    gateway = await asyncio.to_thread(live_gateway, settings, store)
    failed = await asyncio.to_thread(set_up, gateway, case, store)
    if failed:
        return "error", {"total_s": 0.0}, failed
    agent = case_agent(store, config, endpoint, mode, gateway)
    turn = await agent.turn(case.request)
    truth = stage2.Truth.of_robot(gateway.state())  # what the robot reported at the answer
    if turn.started:  # followed as the console follows it, to the robot's arrival
        await agent.follow_up(turn, GOAL_WAIT_S)
    await asyncio.to_thread(_settle, gateway, CONVEYOR_WAIT_S)
    after = stage2.Truth.of_robot(gateway.state())
    return scored(case, turn, truth, after, store)

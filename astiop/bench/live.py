"""Stage 2 on a live ROS 2 robot (`bench run --stage 2 --robot ros2`, e.g. against `astiop sim
node`, or a TurtleBot3 under Nav2): each case is carried over to the robot's own names
(on_robot.py), set up by driving the robot to its start by its roles, and checked against what
the robot reported, a navigation by the robot's arrival."""

from __future__ import annotations

import asyncio
import threading
import time

from astiop.agent import rules
from astiop.agent.intent import Intent
from astiop.bench import stage2
from astiop.bench.case_turn import case_agent, scored
from astiop.bench.on_robot import on_robot
from astiop.config import Settings
from astiop.robot.gateway import RobotGateway
from astiop.ros2.roles import TRIGGER

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
            gw.settled_profile(settings.robot.ros2_timeout_s)  # its roles, read whole
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
    """Drive the robot to the case's start, by its roles; "" or why it could not. A robot with
    no dock starts a "docked" case where it stands."""
    start = case.setup.get("start", "docked")
    profile = gateway.profile
    deadline = time.monotonic() + 15.0
    while gateway.state().pose is None:  # the robot's first pose
        if time.monotonic() > deadline:
            return f"set-up failed: the robot publishes no pose ({profile.name('pose')})"
        time.sleep(0.1)
    for command in rules.plan_intents([Intent("stop")], profile):  # an earlier case's goal
        gateway.run(command, confirm=_yes)
    if profile.has("release"):  # a robot that latches its stop: let go of it
        gateway.run(f"ros2 service call {profile.name('release')} {TRIGGER}", confirm=_yes)
    _settle(gateway, 30)
    truth = stage2.Truth.of_robot(gateway.state())
    if start == "docked":
        if truth.docked or not profile.has("dock"):
            return ""
        intent = Intent("dock")
    else:
        if truth.docked and profile.has("undock"):
            gateway.run(rules.command_for(Intent("undock"), profile), confirm=_yes)
            _settle(gateway, 60)
        x, y, th = stage2._pose_of(store, start)
        intent = Intent("navigate", xy=(x, y), theta=th)
    command = rules.command_for(intent, profile)
    if command is None:
        return f"set-up failed: nothing on this robot does {intent.kind}"
    r = gateway.run(command, confirm=_yes)
    values = r.values if isinstance(r.values, dict) else {}
    if not r.executed or r.error or not values.get("success", values.get("accepted", False)):
        return f"set-up failed: {r.reason or r.error or values.get('message') or values}"
    _settle(gateway, GOAL_WAIT_S)
    return ""


async def live_case(store, settings, config, endpoint, case, mode):
    why = stage2.live_refusal(case)
    if why:
        return "skipped", {"total_s": 0.0, "skipped": why}, ""
    gateway = await asyncio.to_thread(live_gateway, settings, store)

    def locate(name: str) -> tuple[float, float] | None:
        loc = store.get_location(name)
        return (loc.x, loc.y) if loc else None

    case, why = on_robot(case, gateway.profile, locate)  # in the robot's own names
    if why:
        return "skipped", {"total_s": 0.0, "skipped": why}, ""
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

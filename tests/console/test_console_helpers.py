"""The console's helpers built alone, on a bare Textual app: what they need is handed to them."""

from __future__ import annotations

import threading

from textual.app import App

from astiop.agent.models.specs import open_endpoint
from astiop.config import load_settings
from astiop.robot.factory import make_sim_gateway
from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.validation import validate
from astiop.screens.console_recording import ConsoleRecording
from astiop.screens.console_safety import SafetyKeys
from astiop.screens.modals import ConfirmModal
from astiop.services import Services
from astiop.sim.simulator import Simulator
from tests.tui_helpers import wait_for

MOVE = "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{linear: {x: 0.1}}'"


def services(tmp_path, store) -> Services:
    settings = load_settings({"llm": {"model": "rules"}}, env={}, path=tmp_path / "none.toml")
    gateway = make_sim_gateway(settings, store, sim=Simulator(seed=0))
    return Services(settings, store, gateway, open_endpoint("rules"))


def ask_in_a_thread(keys: SafetyKeys, timeout_s: float) -> list[bool]:
    answer: list[bool] = []
    checked = validate(MOVE, astibot_catalog())
    threading.Thread(
        target=lambda: answer.append(keys.confirm_from_thread(checked, timeout_s)), daemon=True
    ).start()
    return answer


async def test_the_safety_keys_ask_y_n_on_any_app_and_silence_is_a_no(tmp_path, store):
    s = services(tmp_path, store)
    app = App()
    keys = SafetyKeys(app, s, None, s.gateway.state)
    try:
        async with app.run_test() as pilot:
            answer = ask_in_a_thread(keys, 30.0)
            await wait_for(pilot, lambda: isinstance(app.screen, ConfirmModal))
            assert "It moves the robot" in app.screen.question
            assert "linear" in app.screen.question  # the command as it will be sent
            await pilot.press("y")
            await wait_for(pilot, lambda: answer)
            assert answer == [True]

            answer = ask_in_a_thread(keys, 0.3)
            await wait_for(pilot, lambda: answer)
            await pilot.pause()
            assert answer == [False] and not isinstance(app.screen, ConfirmModal)
    finally:
        s.gateway.close()


async def test_the_recording_starts_and_stops_on_any_app_and_says_when(tmp_path, store):
    s = services(tmp_path, store)
    app = App()
    changed: list[bool] = []
    recording = ConsoleRecording(app, s, None, lambda: changed.append(True))
    try:
        async with app.run_test() as pilot:
            recording.start(tmp_path / "session.mcap")
            assert recording.recorder is not None and changed == [True]
            recording.start()  # one at a time: a second start changes nothing
            assert changed == [True]
            recording.stop()
            await pilot.pause()
            assert recording.recorder is None and changed == [True, True]
            assert (tmp_path / "session.mcap").stat().st_size > 0
    finally:
        s.gateway.close()

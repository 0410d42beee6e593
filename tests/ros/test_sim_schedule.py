"""The simulator node's publishing thread (robot_programs/ros2_common.py `Schedule`): each send at
its own period, a late tick not caught up, one send's failure said once and no other stopped."""

from __future__ import annotations

import time

from tests.ros import require_ros, until


def test_each_send_at_its_period_and_a_failure_said_once(capfd):
    require_ros()
    from astiop.robot_programs.ros2_common import Schedule

    counts = {"fast": 0, "slow": 0, "broken": 0}

    def count(name: str):
        def send() -> None:
            counts[name] += 1
            if name == "broken":
                raise RuntimeError("a topic that cannot be sent")

        return send

    schedule = Schedule()
    schedule.every(0.02, count("fast"))
    schedule.every(0.1, count("slow"))
    schedule.every(0.02, count("broken"))
    schedule.start()
    try:
        assert until(lambda: counts["slow"] >= 5, 10)
    finally:
        schedule.stop()
    # every period kept to within a loaded machine's slack; none ran ahead of its period
    assert counts["fast"] > 2 * counts["slow"], counts
    assert counts["broken"] > 2 * counts["slow"], counts  # failing, still sent at its rate
    assert capfd.readouterr().err.count("Traceback") == 1  # said once, not at its rate
    stopped = dict(counts)
    time.sleep(0.2)
    assert counts == stopped, "nothing is sent once stopped"


def test_a_late_tick_is_not_caught_up():
    require_ros()
    from astiop.robot_programs.ros2_common import Schedule

    times: list[float] = []

    def slow_once() -> None:
        times.append(time.monotonic())
        if len(times) == 2:
            time.sleep(0.3)  # the thread held up: its next ticks are not sent in a burst

    schedule = Schedule()
    schedule.every(0.05, slow_once)
    schedule.start()
    try:
        assert until(lambda: len(times) >= 6, 10)
    finally:
        schedule.stop()
    gaps = [b - a for a, b in zip(times[2:], times[3:])]
    # no burst of the ticks missed while held up: the first after it is a period from the next
    # (later gaps may be shorter on a loaded machine: a tick late by jitter keeps its phase)
    assert gaps[0] > 0.02, gaps

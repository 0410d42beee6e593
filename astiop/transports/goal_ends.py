"""Any client's navigation goals as the action server's status topic lists them
(action_msgs/msg/GoalStatusArray): a goal seen running and then listed as aborted or canceled
is said as a robot event once — "goal 1a2b3c4d aborted (another client's goal)" — unless this
process sent it (its own goal's end is said with its result)."""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable

from astiop.transports.event_log import EventLog
from astiop.transports.state import ACTIVE_GOAL

ENDS = {5: "canceled", 6: "aborted"}  # action_msgs/msg/GoalStatus STATUS_CANCELED, STATUS_ABORTED
KEPT = 200  # goal ids remembered (a status list holds the goals of the last result_timeout)


class GoalEnds:
    def __init__(self, events: EventLog):
        self.events = events
        self.sent: deque[str] = deque(maxlen=KEPT)  # goal ids (hex) this process sent
        self._running: deque[str] = deque(maxlen=KEPT)

    def listed(self, goals: Iterable[tuple[str, int]]) -> None:
        """The status list as (goal id hex, status): each goal's end said once."""
        for goal_id, status in goals:
            if status in ACTIVE_GOAL:
                if goal_id not in self._running:
                    self._running.append(goal_id)
            elif goal_id in self._running:
                self._running.remove(goal_id)
                how = ENDS.get(status)
                if how is not None and goal_id not in self.sent:
                    self.events.add(
                        "goal", "warning", f"goal {goal_id[:8]} {how} (another client's goal)"
                    )


def status_list(msg) -> list[tuple[str, int]]:
    """(goal id hex, status) of an rclpy GoalStatusArray."""
    return [(bytes(g.goal_info.goal_id.uuid).hex(), int(g.status)) for g in msg.status_list]

"""What travels between the app, its screens and widgets: the robot's state and the agent's turn."""

from __future__ import annotations

from textual.message import Message

from astiop.agent.result import TurnResult
from astiop.transports.state import RobotEvent, RobotState, TopicStat


class RobotStateSampled(Message, bubble=False):
    """The robot's latest state, sampled off the UI thread at ~10 Hz."""

    def __init__(
        self, state: RobotState, events: list[RobotEvent], stats: list[TopicStat] | None = None
    ):
        super().__init__()
        self.state = state
        self.events = events
        self.stats = stats  # every second or so; None in between

    def can_replace(self, message: Message) -> bool:
        # Textual asks the older message whether the newer `message` may supersede it: a burst
        # collapses to the newest, unless this older one carries events or stats
        return isinstance(message, RobotStateSampled) and not self.events and self.stats is None


class AlertsFired(Message, bubble=False):
    """Alerts this console's watches wrote first (rows of the store's alerts)."""

    def __init__(self, alerts: list[dict]):
        super().__init__()
        self.alerts = alerts


class TurnFinished(Message, bubble=False):
    def __init__(self, result: TurnResult, model: str):
        super().__init__()
        self.result = result
        self.model = model


class GoalEnded(Message, bubble=False):
    """How the goal a turn started ended: a follow-up line tied to that turn."""

    def __init__(self, result: TurnResult, text: str):
        super().__init__()
        self.result = result
        self.text = text


class CurrentRobotChanged(Message, bubble=False):
    """The console acts on another robot of the fleet from now (the Fleet screen's enter)."""

    def __init__(self, name: str):
        super().__init__()
        self.name = name

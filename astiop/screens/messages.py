"""What travels between the app, its screens and widgets: the robot's state and the agent's turn
(dataclasses: Textual's Message initialises itself in `__post_init__`)."""

from __future__ import annotations

from dataclasses import dataclass

from textual.message import Message

from astiop.agent.result import TurnResult
from astiop.transports.state import RobotEvent, RobotState, TopicStat


@dataclass
class RobotStateSampled(Message, bubble=False):
    """The robot's latest state, sampled off the UI thread at ~10 Hz."""

    state: RobotState
    events: list[RobotEvent]
    stats: list[TopicStat] | None = None  # every second or so; None in between

    def can_replace(self, message: Message) -> bool:
        # Textual asks the older message whether the newer `message` may supersede it: a burst
        # collapses to the newest, unless this older one carries events or stats
        return isinstance(message, RobotStateSampled) and not self.events and self.stats is None


@dataclass
class AlertsFired(Message, bubble=False):
    """Alerts this console's watches wrote first (rows of the store's alerts)."""

    alerts: list[dict]


@dataclass
class TurnFinished(Message, bubble=False):
    """A chat turn's result, with the model that answered."""

    result: TurnResult
    model: str


@dataclass
class GoalEnded(Message, bubble=False):
    """How the goal a turn started ended: a follow-up line tied to that turn."""

    result: TurnResult
    text: str


@dataclass
class CurrentRobotChanged(Message, bubble=False):
    """The console acts on another robot of the fleet from now (the Fleet screen's enter)."""

    name: str

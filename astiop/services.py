"""What the console's screens work with: the settings, the store, the robot's one door and the
model."""

from __future__ import annotations

from dataclasses import dataclass

from astiop.agent.models.specs import LLMEndpoint
from astiop.config import Settings
from astiop.robot.gateway import RobotGateway
from astiop.store import Store


@dataclass
class Services:
    settings: Settings
    store: Store
    gateway: RobotGateway
    endpoint: LLMEndpoint

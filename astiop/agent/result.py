"""What one agent turn did: the plan, each command's result, the answer, timings, tokens."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from astiop.transports.base import Execution


@dataclass
class TurnResult:
    model: str
    mode: str
    prompt: str
    commands: list[Execution] = field(default_factory=list)
    answer: str = ""
    ttft_s: float | None = None
    total_s: float = 0.0
    llm_s: float = 0.0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    error: str = ""
    raw_replies: list[str] = field(default_factory=list)
    interaction_id: int | None = None
    repaired: bool = False
    refused: str = ""  # the intent gate's reason, when it refused the plan
    model_answer: str = ""  # the interpretation as the model wrote it
    grounding: str = ""  # kept | replaced: why | raw | rules
    started: str = ""  # the goal this turn started and left running, in words
    waited: dict[int, str] = field(default_factory=dict)  # command seq -> how its goal ended
    outcome: str | None = None  # how that goal ended, once it has
    target: tuple[float, float] | None = None  # where that goal is, when known
    mission_id: int | None = None  # the mission this turn started (it runs on after the turn)
    robot: str = ""  # which robot of a fleet the turn was about

    def as_json(self) -> dict[str, Any]:
        return {
            "model": self.model,
            "mode": self.mode,
            "prompt": self.prompt,
            "commands": [
                {
                    "command": c.command,
                    "valid": c.valid,
                    "reason": c.reason,
                    "executed": c.executed,
                    "output": c.output,
                }
                for c in self.commands
            ],
            "answer": self.answer,
            "timings": {"ttft_s": self.ttft_s, "total_s": round(self.total_s, 4)},
            "tokens": {"prompt": self.prompt_tokens, "completion": self.completion_tokens},
            "error": self.error or None,
            "refused": self.refused or None,
            "model_answer": self.model_answer or None,
            "grounding": self.grounding or None,
            "started": self.started or None,
            "outcome": self.outcome,
            "mission_id": self.mission_id,
        }

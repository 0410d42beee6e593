"""What a benchmark suite is made of: its cases, their levels, and its error (`library` loads
and checks the suites)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

LEVELS = ("beginner", "intermediate", "advanced", "expert", "troubleshooting")


class SuiteError(ValueError):
    pass


@dataclass(frozen=True)
class KnowledgeCase:
    id: str
    level: str
    category: str
    prompt: str
    topics: tuple[tuple[str, ...], ...]  # each: accepted spellings, the first is the name
    code: str  # none | python | yaml | xml


@dataclass(frozen=True)
class RobotCase:
    id: str
    category: str
    request: str
    expect: tuple[str, ...]
    setup: dict[str, Any] = field(default_factory=dict)
    answer: tuple[str, ...] = ()
    outcome: dict[str, Any] = field(default_factory=dict)
    base: str = ""  # for a paraphrase: the id of the case it rephrases

    @property
    def level(self) -> str:
        return "multi-step" if len(self.expect) > 1 else "single"

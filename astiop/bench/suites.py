"""The benchmark suites in `prompts/bench/`, loaded and checked."""

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


def stage1() -> tuple[str, tuple[KnowledgeCase, ...]]:
    """The built-in stage-1 suite: its system prompt and cases."""
    from astiop.bench.library import builtin

    suite = builtin("astiop-stage1")
    return suite.system, suite.cases


def stage2() -> tuple[RobotCase, ...]:
    """The built-in stage-2 cases, each paraphrase a case of its own (ID.p1, ID.p2, ...)."""
    from astiop.bench.library import builtin

    return builtin("astiop-stage2").cases

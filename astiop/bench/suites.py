"""The benchmark suites in `prompts/bench/`, loaded and checked."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache
from typing import Any

import yaml

from astiop.resources import prompts_path

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


@cache
def stage1() -> tuple[str, tuple[KnowledgeCase, ...]]:
    data = yaml.safe_load(prompts_path("bench", "stage1.yaml").read_text(encoding="utf-8"))
    cases = []
    for p in data["prompts"]:
        if p["level"] not in LEVELS:
            raise SuiteError(f"stage 1 case {p['id']}: unknown level {p['level']}")
        if not 3 <= len(p["topics"]) <= 5:
            raise SuiteError(f"stage 1 case {p['id']}: needs 3-5 expected topics")
        cases.append(
            KnowledgeCase(
                p["id"],
                p["level"],
                p["category"],
                p["prompt"],
                tuple(tuple(str(s) for s in t) for t in p["topics"]),
                p.get("code", "none"),
            )
        )
    return data["system"], tuple(cases)


@cache
def stage2() -> tuple[RobotCase, ...]:
    """Every case, then its paraphrases as cases of their own (ID.p1, ID.p2, ...)."""
    data = yaml.safe_load(prompts_path("bench", "stage2.yaml").read_text(encoding="utf-8"))
    cases = []
    for c in data["cases"]:
        requests = [c["request"], *c.get("paraphrases", [])]
        for k, request in enumerate(requests):
            cases.append(
                RobotCase(
                    c["id"] if k == 0 else f"{c['id']}.p{k}",
                    c["category"],
                    request,
                    tuple(c["expect"]),
                    c.get("setup", {}),
                    tuple(c.get("answer", [])),
                    c.get("outcome", {}),
                    base=c["id"],
                )
            )
    return tuple(cases)

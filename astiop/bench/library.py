"""Benchmark suites: the built-in ones (`prompts/bench/`) and those imported into the data dir
(`<data dir>/suites/NAME.yaml`), each loaded and checked the same way.

A suite file:
  name: paper-stage1          # letters, digits, '-', '_'
  stage: 1 | 2
  system: the system prompt
  source: where it came from (free text)
  prompts: [...]              # stage 1: {id, level, category, prompt, topics, code}
  cases: [...]                # stage 2, run on the simulator: {id, category, request, expect, ...}
  scenarios: [...]            # stage 2, answered from mock responses (the paper's protocol):
                              #   {id, category, request, command_parts, mock_response,
                              #    interpretation_parts}
  command_prompt, interpret_prompt   # with `scenarios`: the two user prompts, {query} and
                                     # {mock_response} filled in
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import yaml

from astiop.bench.suites import LEVELS, KnowledgeCase, RobotCase, SuiteError
from astiop.resources import prompts_path

MAX_SUITE_BYTES = 5_000_000
NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")
BUILTIN = {
    "astiop-stage1": "stage1.yaml",
    "astiop-stage2": "stage2.yaml",
    "multistep": "multistep.yaml",  # stage 2: missions, scored by order (`bench.multistep`)
    "questions": "questions.yaml",  # stage 2: questions, right / declined / else (`questions`)
    "watches": "watches.yaml",  # stage 2: watches, scored as the questions are
}


@dataclass(frozen=True)
class MockCase:
    """A stage-2 scenario of the paper: a request, a fixed robot reply, the parts expected."""

    id: str
    category: str
    request: str
    command_parts: tuple[str, ...]
    mock_response: str
    interpretation_parts: tuple[str, ...]

    @property
    def level(self) -> str:
        return "scenario"

    @property
    def base(self) -> str:
        return self.id


@dataclass(frozen=True)
class Suite:
    name: str
    stage: int
    system: str
    cases: tuple = ()
    source: str = ""
    path: str = ""
    templates: dict[str, str] = field(default_factory=dict)  # command_prompt, interpret_prompt

    @property
    def kind(self) -> str:
        """knowledge (stage 1), robot (simulator cases) or mock (the paper's scenarios)."""
        if self.stage == 1:
            return "knowledge"
        return "mock" if self.cases and isinstance(self.cases[0], MockCase) else "robot"


def suites_dir(data_dir: Path) -> Path:
    return Path(data_dir) / "suites"


def _strings(value: Any, where: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, (str, int, float)) for v in value):
        raise SuiteError(f"{where}: must be a list of strings")
    return tuple(str(v) for v in value)


def parse_suite(data: Any, where: str, path: str = "") -> Suite:
    """A suite from its YAML data; SuiteError names the file and the case that is wrong."""
    if not isinstance(data, dict):
        raise SuiteError(f"{where}: a suite is a mapping with name, stage, system and cases")
    name = str(data.get("name", ""))
    if not NAME_RE.match(name):
        raise SuiteError(f"{where}: name must be 1-64 letters, digits, '_' or '-'")
    stage = data.get("stage")
    if stage not in (1, 2):
        raise SuiteError(f"{where}: stage must be 1 or 2")
    system = data.get("system")
    if not isinstance(system, str) or not system.strip():
        raise SuiteError(f"{where}: system (the system prompt) is missing")
    try:
        if stage == 1:
            cases = tuple(_knowledge(p, where) for p in _list(data, "prompts", where))
        elif "scenarios" in data:
            cases = tuple(_mock(s, where) for s in _list(data, "scenarios", where))
        else:
            cases = tuple(c for raw in _list(data, "cases", where) for c in _robot(raw, where))
    except (KeyError, TypeError) as exc:
        raise SuiteError(f"{where}: a case lacks {exc}") from None
    ids = [c.id for c in cases]
    if len(set(ids)) != len(ids):
        raise SuiteError(f"{where}: case ids must be unique")
    templates = {k: str(data[k]) for k in ("command_prompt", "interpret_prompt") if k in data}
    if stage == 2 and "scenarios" in data and len(templates) != 2:
        raise SuiteError(f"{where}: scenarios need command_prompt and interpret_prompt")
    return Suite(name, stage, system, cases, str(data.get("source", "")), path, templates)


def _list(data: dict, key: str, where: str) -> list:
    value = data.get(key)
    if not isinstance(value, list) or not value:
        raise SuiteError(f"{where}: {key} must be a non-empty list")
    return value


def _knowledge(p: dict, where: str) -> KnowledgeCase:
    if p["level"] not in LEVELS:
        raise SuiteError(f"{where}: case {p['id']}: level must be one of {', '.join(LEVELS)}")
    topics = p["topics"]
    if not isinstance(topics, list) or not topics:
        raise SuiteError(f"{where}: case {p['id']}: topics must be a non-empty list")
    spellings = tuple(
        _strings(t, f"case {p['id']} topics") if isinstance(t, list) else (str(t),) for t in topics
    )
    return KnowledgeCase(
        str(p["id"]), p["level"], str(p["category"]), str(p["prompt"]), spellings,
        str(p.get("code", "none")),
    )  # fmt: skip


def _robot(c: dict, where: str) -> list[RobotCase]:
    """A simulator case, then its paraphrases as cases of their own (ID.p1, ID.p2, ...)."""
    requests = [c["request"], *c.get("paraphrases", [])]
    return [
        RobotCase(
            str(c["id"]) if k == 0 else f"{c['id']}.p{k}",
            str(c["category"]),
            str(request),
            _strings(c["expect"], f"case {c['id']} expect"),
            c.get("setup", {}),
            tuple(c.get("answer", [])),
            c.get("outcome", {}),
            base=str(c["id"]),
        )
        for k, request in enumerate(requests)
    ]


def _mock(s: dict, where: str) -> MockCase:
    return MockCase(
        str(s["id"]),
        str(s["category"]),
        str(s["request"]),
        _strings(s["command_parts"], f"case {s['id']} command_parts"),
        str(s["mock_response"]),
        _strings(s["interpretation_parts"], f"case {s['id']} interpretation_parts"),
    )


def _suite_yaml(text: str) -> Any:
    """A suite file's YAML: bounded in size, with no aliases (no alias bombs)."""
    if len(text) > MAX_SUITE_BYTES:
        raise SuiteError(f"larger than {MAX_SUITE_BYTES // 1_000_000} MB")
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    if any(isinstance(ev, yaml.AliasEvent) for ev in yaml.parse(text, Loader=loader)):
        raise SuiteError("YAML aliases (*name) are not allowed in a suite")
    return yaml.load(text, Loader=loader)  # noqa: S506 (a safe loader)


def read_suite_file(path: Path) -> Suite:
    return parse_suite(suite_data(path), str(path), str(path))


def suite_data(path: Path) -> Any:
    """A suite file's YAML data; SuiteError when it cannot be read."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SuiteError(f"cannot read {path}: {getattr(exc, 'strerror', None) or exc}") from None
    try:
        data = _suite_yaml(text)
    except (SuiteError, yaml.YAMLError, RecursionError) as exc:
        why = (str(exc).splitlines() or ["unreadable"])[0][:160]
        raise SuiteError(f"{path}: not a YAML suite ({why})") from None
    return data


@cache
def builtin(name: str) -> Suite:
    path = prompts_path("bench", BUILTIN[name])
    data = _suite_yaml(path.read_text(encoding="utf-8"))
    data = {"name": name, "stage": 1 if name.endswith("1") else 2, "source": "built in", **data}
    data.setdefault("system", "You operate a warehouse robot.")  # stage 2 uses the agent's
    return parse_suite(data, str(path), str(path))


def all_suites(data_dir: Path) -> tuple[list[Suite], list[str]]:
    """Built-in, then imported suites; and the imported files that could not be read."""
    found = [builtin(name) for name in BUILTIN]
    problems = []
    for path in sorted(suites_dir(data_dir).glob("*.yaml")):
        try:
            found.append(read_suite_file(path))
        except SuiteError as exc:
            problems.append(str(exc))
    return found, problems


def load_suite(name_or_path: str, data_dir: Path) -> Suite:
    """A suite by name (built in or imported) or by the path of a suite file."""
    if name_or_path in BUILTIN:
        return builtin(name_or_path)
    if NAME_RE.match(name_or_path):
        path = suites_dir(data_dir) / f"{name_or_path}.yaml"
        if path.is_file():
            return read_suite_file(path)
    path = Path(name_or_path).expanduser()
    if path.is_file():
        return read_suite_file(path)
    known = ", ".join(s.name for s in all_suites(data_dir)[0])
    raise SuiteError(f"no suite named or at '{name_or_path}' (known: {known})")

"""System prompts from `prompts/`, filled with the catalog and the named locations."""

from __future__ import annotations

import json
import re
from functools import cache, lru_cache

import yaml

from astiop.agent.tools import OPERATOR_ONLY, READABLE_EXCLUDED, Tool
from astiop.resources import prompts_path
from astiop.ros2.catalog import Catalog


@cache
def template(name: str) -> str:
    return prompts_path(f"{name}.md").read_text(encoding="utf-8")


def fill(text: str, **values: str) -> str:
    """Replace {name} placeholders; every other brace (JSON examples) stays as written."""
    for key, value in values.items():
        text = text.replace("{" + key + "}", value)
    return text


def command_prompt(catalog: Catalog, locations: list[str]) -> str:
    """The robot's topics and services for command mode; on a robot that is not the ASTIbot,
    those that play a role only, each said by its role (a Nav2 graph has a hundred others)."""
    profile = catalog.profile
    roles = {m.name: r for r, m in profile.matches.items() if m.name} if profile else {}
    own = profile is None or profile.make == "astibot"
    topics = "\n".join(
        f"- {t.name}: {roles[t.name].replace('_', ' ')} ({t.type})"
        if not own
        else f"- {t.name}: {t.description}"
        for t in catalog.topics.values()
        if t.name not in READABLE_EXCLUDED and (own or t.name in roles)
    )
    services = "\n".join(
        f"- {s.name} {s.type}: "
        + (s.description if own else roles.get(s.name, "").replace("_", " "))
        for s in catalog.services.values()
        if s.name not in OPERATOR_ONLY and (own or s.name in roles)
    )
    return fill(
        template("agent_command"),
        topics=topics,
        services=services,
        locations=", ".join(locations) or "none",
    )


def tool_prompt(tools: list[Tool]) -> str:
    """Every tool of the robot, the same for every request, so a server's prompt cache keeps
    it and the examples; the request's own tools are held by the grammar and the schema."""
    return fill(template("agent_tool"), tools=", ".join(t.id for t in tools))


@lru_cache(maxsize=1)
def examples() -> list[dict]:
    return yaml.safe_load(prompts_path("agent_examples.yaml").read_text(encoding="utf-8"))


def example_messages(mode: str) -> list[dict[str, str]]:
    """The examples as earlier chat turns, in the reply format of `mode`."""
    messages = []
    for ex in examples():
        reply = {"steps": [ex["tool"]]} if mode == "tool" else {"commands": [ex["command"]]}
        messages += [
            {"role": "user", "content": ex["request"]},
            {"role": "assistant", "content": json.dumps(reply, separators=(",", ":"))},
        ]
    return messages


def interpret_prompt() -> str:
    return template("agent_interpret")


_SOURCE = re.compile(r"\s(/[A-Za-z0-9_/]+)")


def labelled(results: str) -> str:
    """Each command line above its indented result cut to the topic or service it used: ~10
    prompt tokens fewer per command (0.1 s of a turn on one core). A parameter's command stays
    whole: its result ("Double value is: 0.8") does not name the parameter."""
    lines = results.split("\n")
    for i, line in enumerate(lines[:-1]):
        cut = line.startswith("ros2 ") and not line.startswith("ros2 param ")
        found = _SOURCE.search(line) if cut else None
        if found and lines[i + 1].startswith("  "):
            lines[i] = found.group(1)
    return "\n".join(lines)


def interpret_user(request: str, results: str) -> str:
    """Six tokens fewer than "Operator request: ...\\n\\nResults: ...\\n\\nAnswer:" (60 ms of a
    turn on one core), and as good on the held-out requests: 30/32 right, 29 answers in the
    model's words against 27."""
    return f"Request: {request}\nResults:\n{labelled(results)}"


@lru_cache(maxsize=1)
def interpret_examples() -> list[dict]:
    return yaml.safe_load(prompts_path("agent_interpret_examples.yaml").read_text(encoding="utf-8"))


def interpret_messages(request: str, results: str) -> list[dict[str, str]]:
    """The interpretation call: the fixed prompt and worked examples (a prefix the server's
    cache keeps), then this turn's request and results."""
    messages = [{"role": "system", "content": interpret_prompt()}]
    for ex in interpret_examples():
        messages += [
            {"role": "user", "content": interpret_user(ex["request"], ex["results"])},
            {"role": "assistant", "content": ex["answer"]},
        ]
    return [*messages, {"role": "user", "content": interpret_user(request, results)}]

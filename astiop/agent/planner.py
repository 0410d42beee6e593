"""Planning: the model's reply to a request, read into commands, repaired once at most.

A reply is asked for again, once, with the reason, when it cannot be read, when one of its
commands is rejected, or when the intent gate says it does not do what was asked.
"""

from __future__ import annotations

import contextlib
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from astiop.agent import prompts
from astiop.agent.intent import Intent
from astiop.agent.models.llm import LLMProtocolError
from astiop.agent.models.reply_stream import Completion
from astiop.agent.replies import ReplyError, commands_from_reply, steps_from_reply
from astiop.agent.result import TurnResult
from astiop.agent.tools import (
    build_tools,
    command_grammar,
    command_schema,
    narrow,
    tool_grammar,
    tool_schema,
)
from astiop.robot.safety import Review
from astiop.ros2.catalog import Catalog

Messages = list[dict[str, str]]
Ask = Callable[[Messages], Awaitable[Completion]]


@dataclass
class PlanRequest:
    """What the model is sent, and how its reply is read."""

    messages: Messages
    schema: dict
    grammar: str
    parse: Callable[[str], list[str]]


def plan_request(
    mode: str,
    catalog: Catalog,
    locations: list[str],
    request: str,
    intents: list[Intent],
    history: list[tuple[str, str]],
    narrow_tools: bool = True,
) -> PlanRequest:
    """The messages of one planning call: the prompt of the mode and its examples (the same for
    every request, so a server's prompt cache keeps them), earlier turns, then the request.
    `intents` is the request as classified (tool mode offers only the tools that fit them)."""
    if mode == "tool":
        every = build_tools(catalog, locations)
        tools = narrow(every, intents) if narrow_tools else every
        system, schema, grammar = (
            prompts.tool_prompt(every),
            tool_schema(tools),
            tool_grammar(tools),
        )

        def parse(text: str) -> list[str]:
            return steps_from_reply(text, tools)
    else:
        system, schema = prompts.command_prompt(catalog, locations), command_schema()
        grammar, parse = command_grammar(), commands_from_reply
    messages = [{"role": "system", "content": system}, *prompts.example_messages(mode)]
    for past_request, past_answer in history:
        messages += [
            {"role": "user", "content": past_request},
            {"role": "assistant", "content": past_answer},
        ]
    messages.append({"role": "user", "content": request})
    return PlanRequest(messages, schema, grammar, parse)


async def plan(
    req: PlanRequest,
    ask: Ask,
    review: Callable[[str], Awaitable[Review]],
    gate_reason: Callable[[list[str]], Awaitable[str | None]],
    result: TurnResult,
) -> list[str]:
    """The commands of the model's plan; LLMProtocolError when even the repair is unusable."""
    c = await ask(req.messages)
    try:
        commands = parsed(req.parse, c.text)
    except ReplyError as exc:
        return await _repair(req, c.text, str(exc), ask, result)
    for cmd in commands:
        checked = (await review(cmd)).checked
        if not checked.valid:
            reason = f"the command `{cmd}` was rejected: {checked.reason}"
            with contextlib.suppress(LLMProtocolError):  # else the first plan, recorded rejected
                return await _repair(req, c.text, reason, ask, result)
            return commands
    refused = await gate_reason(commands)
    if refused:
        with contextlib.suppress(LLMProtocolError):  # else the gate refuses the first plan
            return await _repair(req, c.text, refused, ask, result)
    return commands


async def _repair(
    req: PlanRequest, reply: str, reason: str, ask: Ask, result: TurnResult
) -> list[str]:
    result.repaired = True
    retry = req.messages + [
        {"role": "assistant", "content": reply},
        {
            "role": "user",
            "content": f"That reply could not be used: {reason}. Answer again with JSON only.",
        },
    ]
    c = await ask(retry)
    try:
        return parsed(req.parse, c.text)
    except ReplyError as exc:
        raise LLMProtocolError(f"the model's reply could not be used: {exc}") from None


def parsed(parse: Callable[[str], list[str]], text: str) -> list[str]:
    """A reply's commands; whatever a hostile reply breaks becomes a ReplyError."""
    try:
        return parse(text)
    except ReplyError:
        raise
    except (ValueError, TypeError, OverflowError, RecursionError) as exc:
        raise ReplyError(f"the reply could not be read ({type(exc).__name__})") from None

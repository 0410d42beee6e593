"""The turn's interpretation: the results said back by the rules, or by the model held to what
the robot reported (`grounding`); its reply is never turned into commands."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from astiop.agent import grounding, prompts, rules
from astiop.agent.answer_grammar import answer_grammar
from astiop.agent.facts import facts_of
from astiop.agent.models.reply_stream import Completion
from astiop.agent.models.specs import LLMEndpoint
from astiop.agent.result import TurnResult
from astiop.agent.summaries import summarize

# the agent's one way to the model: (messages, schema, result, emit, kind, grammar=,
# max_tokens=), the reply streamed to `emit` as `kind` and accounted in `result`
Ask = Callable[..., Awaitable[Completion]]
Emit = Callable[[str, Any], None]


class Interpreter:
    """Says a turn's results back: by the rules, or by the model asked through `ask` and held
    to what the robot reported (`style` "grounded"), or in the model's own words ("raw")."""

    def __init__(self, ask: Ask, style: str = "grounded", max_tokens: int = 96) -> None:
        if style not in ("grounded", "raw"):
            raise ValueError(f"interpretation must be 'grounded' or 'raw', not '{style}'")
        self.ask = ask
        self.style = style
        self.max_tokens = max_tokens  # of the model's answer

    async def interpret(
        self, endpoint: LLMEndpoint, request: str, result: TurnResult, emit: Emit, fallback: str
    ) -> str:
        """The answer to `request` from `result`'s commands; `fallback` labels an answer the
        model did not write (it is not asked)."""
        if endpoint.is_rules or fallback:
            answer = rules.interpret(request, result.commands, _waited_lines(result))
            if result.started:
                answer += f" | {result.started}"
            answer = fallback + answer  # the label of an answer the model did not write
            result.grounding = "rules"
            emit("answer_token", answer)
            return answer
        reason = grounding.nothing_ran(result.commands)
        if reason is not None:  # nothing to interpret: the reason, not a model's story
            result.grounding = "nothing ran"
            emit("answer_token", reason)
            return reason
        results = "\n".join(summarize(ex) for ex in result.commands)  # some command ran
        results += "".join(f"\n{line}" for line in _waited_lines(result))
        if result.started:
            results += f"\n{result.started} (the robot is on its way; it has not arrived)"
        outcome = "succeeded" if "succeeded" in result.waited.values() else None
        facts = facts_of(
            request, result.commands, outcome, [result.started, *_waited_lines(result)]
        )
        messages = prompts.interpret_messages(request, results)
        grammar = None  # llama.cpp servers: the words and figures this turn's results allow
        if self.style == "grounded" and endpoint.local:
            ran = [ex for ex in result.commands if ex.executed and not ex.error]
            commanded = all(ex.provenance == "commanded" for ex in ran)
            grammar = answer_grammar(request, results, facts.words, facts.kinds, commanded)
        c = await self.ask(
            messages,
            None,
            result,
            emit,
            "answer_token",
            grammar=grammar,
            max_tokens=self.max_tokens,
        )
        text = result.model_answer = c.text.strip()
        if self.style == "raw":
            result.grounding = "raw"
            return _with_started(text, result.started)
        dropped = 0
        if c.finish_reason in grounding.REPLY_CUT:
            reason = f"the reply was cut: {grounding.REPLY_CUT[c.finish_reason]}"
        else:
            text, reason, dropped = grounding.grounded(text, facts, result.commands)
        if reason is None:
            result.grounding = f"kept, {dropped} part(s) dropped" if dropped else "kept"
            if dropped:
                emit("answer_trimmed", text)
            return _with_started(text, result.started)
        result.grounding = f"replaced: {reason}"
        answer = grounding.factual_answer(result.commands, result.started, _waited_lines(result))
        emit("answer_replaced", answer)
        return answer


def _waited_lines(result: TurnResult) -> list[str]:
    return [
        f"{result.commands[seq].command}: goal {outcome}" for seq, outcome in result.waited.items()
    ]


def _with_started(text: str, started: str) -> str:
    return f"{text}\n{started}" if started else text

"""Stage 1: one ROS-knowledge prompt to one model, scored (quality, coverage, speed)."""

from __future__ import annotations

import time
from typing import Any

from astiop.agent.models.llm import LLMError, LLMTimeout
from astiop.agent.models.specs import LLMEndpoint
from astiop.bench import scoring
from astiop.bench.suites import KnowledgeCase

RULES_REPLY = "The rules baseline answers robot requests only, not ROS questions."


async def run_case(
    endpoint: LLMEndpoint, system: str, case: KnowledgeCase, max_tokens: int
) -> tuple[str, dict[str, Any], str]:
    """(outcome, metrics, response); outcome is ok, error or timeout."""
    t0 = time.perf_counter()
    if endpoint.is_rules:
        text, tps = RULES_REPLY, 0.0
    else:
        try:
            c = await endpoint.client().chat(
                [{"role": "system", "content": system}, {"role": "user", "content": case.prompt}],
                max_tokens=max_tokens,
                temperature=0.0,
            )
        except LLMTimeout as exc:
            return "timeout", _failed(t0), str(exc)
        except LLMError as exc:
            return "error", _failed(t0), str(exc)
        text, tps = c.text, c.tokens_per_s or 0.0
    code = scoring.check_code(text)
    metrics = {
        "q": scoring.quality(text, case.topics, case.code),
        "c": scoring.coverage(text, case.topics),
        "tps": tps,
        "words": len(text.split()),
        "code_blocks": code.blocks,
        "code_valid": code.valid,
        "total_s": time.perf_counter() - t0,
    }
    return ("ok" if text.strip() else "error"), metrics, text


def _failed(t0: float) -> dict[str, Any]:
    return {
        "q": 0.0,
        "c": 0.0,
        "tps": 0.0,
        "words": 0,
        "code_blocks": 0,
        "code_valid": 0,
        "total_s": time.perf_counter() - t0,
    }

"""The paper's benchmark protocol, reproduced exactly (test_ros_agents.py and
test_ros_command_agent.py of mihaidanielPavel/model_runner_web_app).

Run conditions: one non-streaming `POST .../chat/completions` per call with the system prompt
and the user prompt, no max_tokens, no temperature; stage 1 waits 300 s, stage 2 120 s. Time is
the request's wall time; tokens/s is completion tokens over that wall time. Stage 2 makes two
independent calls per scenario (the command; the interpretation of the fixed mock response) and
executes nothing.

Per-case scores, as the scripts compute them:
  stage 1  coverage = 100 x share of expected topics found (case-insensitive substrings)
           quality  = 25 each for: length > 100 chars, length > 300, code present ("def ",
                      "class " or a code fence), coverage > 50
  stage 2  command score = 100 x share of expected parts found; valid when the reply holds
           "ros2", one of topic/service/node/param, and the score >= 60
           interpretation score likewise; valid when the reply has more than 5 words, "ros2"
           is absent or occurs at least twice (the script's "not just a command"), and the
           score >= 40
"""

from __future__ import annotations

import time
from typing import Any

import httpx

STAGE1_TIMEOUT_S = 300.0
STAGE2_TIMEOUT_S = 120.0


async def completion(
    url: str, model: str, system: str, prompt: str, timeout_s: float
) -> dict[str, Any]:
    """One request as the scripts send it: status success, error or timeout."""
    payload = {
        "model": model,
        "messages": [{"role": "system", "content": system}, {"role": "user", "content": prompt}],
        "stream": False,
    }
    start = time.perf_counter()
    try:
        async with httpx.AsyncClient(timeout=timeout_s) as client:
            resp = await client.post(url, json=payload)
        total = time.perf_counter() - start
        if resp.status_code != 200:
            return _failed("error", f"HTTP {resp.status_code}: {resp.text[:300]}", total)
        body = resp.json()
        choices = body.get("choices") or [{}]
        text = (choices[0].get("message") or {}).get("content") or ""
        usage = body.get("usage") or {}
        tokens = int(usage.get("completion_tokens") or 0)
        return {
            "status": "success",
            "response": text,
            "total_time": total,
            "tokens": tokens,
            "tokens_per_sec": tokens / total if total > 0 else 0.0,
            "prompt_tokens": int(usage.get("prompt_tokens") or 0),
            "total_tokens": int(usage.get("total_tokens") or 0),
            "error": "",
        }
    except httpx.TimeoutException:
        return _failed("timeout", "Request timeout", timeout_s)
    except (httpx.HTTPError, ValueError, AttributeError) as exc:
        return _failed("error", str(exc)[:300] or type(exc).__name__, time.perf_counter() - start)


def _failed(status: str, error: str, total: float) -> dict[str, Any]:
    return {
        "status": status,
        "response": "",
        "total_time": total,
        "tokens": 0,
        "tokens_per_sec": 0.0,
        "prompt_tokens": 0,
        "total_tokens": 0,
        "error": error,
    }


# -- per-case scores --------------------------------------------------------------------------
def share_found(text: str, parts) -> float:
    lowered = text.lower()
    found = sum(1 for part in parts if part.lower() in lowered)
    return found / len(parts) * 100 if parts else 0


def stage1_scores(response: str, topics) -> dict[str, Any]:
    coverage = share_found(response, topics)
    has_code = "def " in response or "class " in response or "```" in response
    length = len(response)
    quality = 25 * ((length > 100) + (length > 300) + has_code + (coverage > 50))
    return {
        "coverage_score": coverage,
        "quality_score": quality,
        "topics_covered": sum(1 for t in topics if t.lower() in response.lower()),
        "total_topics": len(topics),
        "has_code": has_code,
        "response_length": length,
    }


def command_scores(response: str, parts) -> tuple[bool, float]:
    score = share_found(response, parts)
    lowered = response.lower()
    has_verb = any(verb in lowered for verb in ("topic", "service", "node", "param"))
    return ("ros2" in lowered and has_verb and score >= 60), score


def interpretation_scores(response: str, parts) -> tuple[bool, float]:
    score = share_found(response, parts)
    lowered = response.lower()
    not_just_command = "ros2" not in lowered or len(lowered.split("ros2")) > 2
    return (len(response.split()) > 5 and not_just_command and score >= 40), score


# -- cases ------------------------------------------------------------------------------------
async def stage1_case(url: str, model: str, system: str, case) -> tuple[str, dict, str]:
    """(outcome, metrics, response) of one knowledge prompt."""
    topics = [spellings[0] for spellings in case.topics]
    r = await completion(url, model, system, case.prompt, STAGE1_TIMEOUT_S)
    scores = stage1_scores(r["response"], topics) if r["status"] == "success" else {
        "coverage_score": 0, "quality_score": 0, "topics_covered": 0,
        "total_topics": len(topics), "has_code": False, "response_length": 0,
    }  # fmt: skip
    metrics = {
        "q": scores["quality_score"],
        "c": scores["coverage_score"],
        "tps": r["tokens_per_sec"],
        "total_s": r["total_time"],
        "status": r["status"],
        "total_time": r["total_time"],
        "tokens": r["tokens"],
        "tokens_per_sec": r["tokens_per_sec"],
        "prompt_tokens": r["prompt_tokens"],
        "total_tokens": r["total_tokens"],
        "expected_topics": topics,
        "error": r["error"],
        **scores,
    }
    return _outcome(r["status"]), metrics, r["response"]


async def stage2_case(url: str, model: str, suite, case) -> tuple[str, dict, str]:
    """(outcome, metrics, interpretation) of one scenario: two independent calls."""
    ask = suite.templates["command_prompt"].format(query=case.request)
    r1 = await completion(url, model, suite.system, ask, STAGE2_TIMEOUT_S)
    metrics: dict[str, Any] = {
        "command_prompt": ask,
        "command_response": r1["response"],
        "command_valid": False,
        "command_score": 0,
        "mock_data": case.mock_response,
        "interpret_prompt": "",
        "interpretation_response": "",
        "interpretation_valid": False,
        "interpretation_score": 0,
        "expected_command_parts": list(case.command_parts),
        "expected_interpretation_parts": list(case.interpretation_parts),
        "status": r1["status"],
        "stage": "command_generation",
        "total_time": r1["total_time"],
        "total_tokens": 0,
        "error": r1["error"],
    }
    if r1["status"] == "success":
        valid, score = command_scores(r1["response"], case.command_parts)
        metrics.update(command_valid=valid, command_score=score)
        tell = suite.templates["interpret_prompt"].format(
            query=case.request, mock_response=case.mock_response
        )
        r2 = await completion(url, model, suite.system, tell, STAGE2_TIMEOUT_S)
        metrics.update(
            interpret_prompt=tell,
            interpretation_response=r2["response"],
            status=r2["status"],
            stage="interpretation" if r2["status"] != "success" else "complete",
            total_time=r1["total_time"] + r2["total_time"],
            error=r2["error"],
        )
        if r2["status"] == "success":
            valid, score = interpretation_scores(r2["response"], case.interpretation_parts)
            metrics.update(
                interpretation_valid=valid,
                interpretation_score=score,
                total_tokens=r1["tokens"] + r2["tokens"],
            )
    metrics.update(
        command=metrics["command_score"],
        interpretation=metrics["interpretation_score"],
        c_valid=metrics["command_valid"],
        i_valid=metrics["interpretation_valid"],
        total_s=metrics["total_time"],
        tokens=metrics["total_tokens"],
    )
    return _outcome(metrics["status"]), metrics, metrics["interpretation_response"]


def _outcome(status: str) -> str:
    return {"success": "ok", "timeout": "timeout"}.get(status, "error")

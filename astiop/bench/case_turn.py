"""A stage-2 case's turn, the same on the simulator and on a live robot: the agent it runs with
(every actuation confirmed, no fallback) and how the turn is scored."""

from __future__ import annotations

from astiop.agent.turn import Agent
from astiop.bench import stage2


def case_agent(store, config, endpoint, mode, gateway) -> Agent:
    return Agent(
        gateway,
        endpoint,
        None,
        mode=mode,
        max_tokens=min(config.max_tokens, 160),
        confirm=lambda _c: True,
        fallback=False,
        places={loc.name: (loc.x, loc.y) for loc in store.list_locations()},
        interpretation=config.interpretation,
    )


def scored(case, turn, truth, after, store):
    score = stage2.score_case(case, turn, truth, after, store)
    metrics = {
        "command": score.command,
        "interpretation": score.interpretation,
        "c_valid": score.c_valid,
        "i_valid": score.i_valid,
        "total_s": turn.total_s,
        "ttft_s": turn.ttft_s,
        "tokens": turn.completion_tokens,
        "base": case.base or case.id,
        "wrong_actuations": len(stage2.wrong_actuations(turn, case.expect)),
        "refused": bool(turn.refused),
        "grounding": turn.grounding,
        **score.details,
    }
    outcome = "error" if turn.error and not turn.commands else "ok"
    return outcome, metrics, turn.answer

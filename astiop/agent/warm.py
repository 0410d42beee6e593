"""Warming the embedded model for this robot: its fixed prompts evaluated once, at start.

The planning prompt is generated from the robot's profile and its map's places, so a robot never
seen before (or a fresh install) has no saved prefix in the prompt cache, and its first answer
waits for the whole prompt to be evaluated (18.8 s measured on 2 cores). Evaluated in the
background as soon as the console opens, the prefix is in the model's slot (and saved to disk
for the next process) before the operator's first question, which then evaluates its own words
only.

A question asked meanwhile would wait for the warm-up (15.8-24.9 s asked one second after the
console opens, `benchmarks/first_answer_console.py`). One that only reads the robot ("what is
the battery level?") is answered at once from the robot's readings by the rules, labelled
`WARMING` (`readings_meanwhile`); any other waits its turn at the server: never longer than it
would have.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from astiop.agent import planner, prompts
from astiop.agent.intent import Intent
from astiop.agent.models.specs import LLMEndpoint
from astiop.robot.gateway import RobotGateway
from astiop.store import Store

WARM_REQUEST = "status"  # any request: only the prefix before it is kept
WARMING = "[model warming up] "  # an answer the rules read from the robot meanwhile
READ_ONLY = frozenset({"read", "list"})  # intents that only look


def warmable(endpoint: LLMEndpoint) -> bool:
    """Only an embedded model keeps a prompt cache astiop can fill (a server's is its own)."""
    return endpoint.local and not endpoint.is_rules


async def warm(endpoint: LLMEndpoint, gateway: RobotGateway, store: Store | None, mode: str):
    """Evaluates the planning prompt of `mode` for this robot and the interpretation prompt;
    returns the seconds it took, or None when there is nothing to warm. `endpoint.warming`
    holds meanwhile."""
    if not warmable(endpoint):
        return None
    import asyncio

    t0 = time.perf_counter()
    endpoint.warming = True
    try:
        client = await asyncio.to_thread(endpoint.client)
        places = [loc.name for loc in store.list_locations()] if store is not None else []
        plan = planner.plan_request(mode, gateway.catalog, places, WARM_REQUEST, [], [])
        for messages in (plan.messages, prompts.interpret_messages(WARM_REQUEST, "")):
            await client.chat(messages, max_tokens=1)
    finally:
        endpoint.warming = False
    return time.perf_counter() - t0


def readings_meanwhile(
    endpoint: LLMEndpoint, intents: list[Intent], plan: Callable[[list[Intent]], list[str]]
) -> list[str]:
    """While the model warms up, the rules' reads for a request that only reads the robot, each
    of its intents planned (`plan`: the rules planner); [] otherwise: the model plans it."""
    if not getattr(endpoint, "warming", False) or not intents:
        return []
    if any(i.kind not in READ_ONLY for i in intents):
        return []
    commands = plan(intents)
    return commands if len(commands) == len(intents) else []

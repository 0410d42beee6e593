"""A request that is a watch ("tell me when the battery is below 20 %"): read into a typed
watch, checked against the robot's roles, stored, and said back in one sentence; a watch that
cannot be kept is one line and nothing is stored. Any other request is planned as before."""

from __future__ import annotations

from typing import Any

from astiop.agent.intent import resolve_place
from astiop.watches.model import WatchError, validate
from astiop.watches.words import watch_from_words


def kept(request: str, agent: Any) -> str | None:
    """The answer when the request is a watch (kept or not), else None."""
    try:
        places = agent.places()  # the store's places of the robot's map
        watch = watch_from_words(
            request, agent.robot, places, lambda said: resolve_place(said, list(places)),
            (agent.robot,) if agent.robot else (),
        )  # fmt: skip
        if watch is None:
            return None
        validate(watch, agent.gateway.profile)
    except WatchError as exc:
        return f"Not watched: {exc}; nothing was stored."
    if agent.store is None:
        return (  # the watch understood all the same (the bench's turns have no database)
            "Not watched: watches are kept in astiop's database, and there is none here; "
            f"it would be: I will tell you when {watch.sentence()}."
        )
    watch_id = agent.store.add_watch(**watch.row())
    return f"Watch {watch_id}: I will tell you when {watch.sentence()}."

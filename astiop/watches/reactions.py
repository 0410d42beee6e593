"""A watch's reaction that moves the robot: mission steps the operator approved when the watch
was made, run once by the process that wrote the watch's alert (so once across processes), and
refused while the E-STOP holds. Control of a robot no one held is taken for the mission and let
go of when it ends. Another operator's control and every step's own checks are the
mission's (the gateway refuses them as it refuses any command)."""

from __future__ import annotations

import json
import logging
import threading
import time
from typing import Any

from astiop.missions.steps import Step, describe

log = logging.getLogger("astiop.watches")
MAX_STEPS = 10


class ReactionError(ValueError):
    """A reaction that cannot be kept, in one line."""


def mission_reaction(steps: list[Step], approved_by: str) -> str:
    """The reaction as the watches table keeps it."""
    if not steps or len(steps) > MAX_STEPS:
        raise ReactionError(f"a reaction is 1 to {MAX_STEPS} mission steps")
    return json.dumps(
        {"steps": [s.to_json() for s in steps], "approved_by": approved_by, "at": time.time()}
    )


def reaction_steps(reaction: str) -> list[Step] | None:
    """The mission steps of a reaction (None: it only notifies); ReactionError if unreadable."""
    if reaction == "notify":
        return None
    try:
        kept = json.loads(reaction)
        steps = [Step.from_json(s) for s in kept["steps"]]
        approved = str(kept["approved_by"])
    except (ValueError, KeyError, TypeError) as exc:
        raise ReactionError(f"a reaction is 'notify' or approved mission steps ({exc})") from None
    if not steps or len(steps) > MAX_STEPS or not approved:
        raise ReactionError(f"a reaction is 1 to {MAX_STEPS} approved mission steps")
    return steps


def reaction_words(reaction: str) -> str:
    steps = reaction_steps(reaction)
    return "notify" if steps is None else f"then {describe(steps)}"


def react(gateway: Any, store: Any, alert: dict, e_stopped: bool) -> str | None:
    """Run the reaction of the watch that fired `alert` (written by this process); what was
    done, in one line, kept as an event (None: the watch only notifies)."""
    if alert.get("watch_id") is None:
        return None
    try:
        row = store.watch(alert["watch_id"])
    except Exception as exc:  # noqa: BLE001 - a busy store: the alert is said all the same
        return f"watch {alert['watch_id']}: reaction not run: its watch not read ({exc})"
    if row is None or row["reaction"] == "notify":
        return None
    try:
        steps = reaction_steps(row["reaction"])
    except ReactionError as exc:
        said = f"watch {row['id']}: reaction not run: {exc}"
        steps = None
    if steps is not None and (e_stopped or gateway.latched):
        said = f"watch {row['id']}: reaction not run: the E-STOP holds ({describe(steps)})"
        steps = None
    if steps is not None:
        from astiop.missions.runner import MissionError, MissionRunner

        lease = getattr(gateway, "lease", None)
        borrowed = lease is not None and not lease.held  # taken by the mission's first motion
        try:
            runner = MissionRunner(gateway, store)
            mission = runner.start(steps, f"watch {row['id']}: {alert['message']}", "watch")
            said = f"watch {row['id']}: mission {mission} started ({describe(steps)})"
            if borrowed:
                threading.Thread(
                    target=_give_back, args=(runner, gateway), name="reaction", daemon=True
                ).start()
        except (MissionError, Exception) as exc:  # noqa: BLE001 - the watcher goes on
            said = f"watch {row['id']}: reaction not run: {exc}"
    try:
        store.add_event("watch", said, severity="warning" if "not run" in said else "info")
    except Exception as exc:  # noqa: BLE001 - said to the caller all the same
        log.info("the reaction's outcome not kept: %s", exc)
    return said


def _give_back(runner: Any, gateway: Any) -> None:
    """Control a reaction took (the robot free before it) is let go of when its mission ends:
    a headless watcher does not keep every operator's console from the robot."""
    runner.wait()
    gateway.let_go_of_control()

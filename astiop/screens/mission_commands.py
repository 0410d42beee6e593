"""The console's mission controls (the palette's "Mission: …" commands, the Dashboard's keys):
pause, resume and cancel the robot's live mission. Each is asked through the store, so the
process driving the mission obeys whichever it is (this console, `astiop chat --no-wait`'s)."""

from __future__ import annotations

from collections.abc import Iterable
from functools import partial
from typing import Any

from textual.app import SystemCommand

from astiop.missions import view
from astiop.missions.runner import robot_key
from astiop.screens.base import services_of


def live_mission(app: Any) -> dict[str, Any] | None:
    """The robot's running, paused or queued mission, as the views show it; None: none."""
    store = services_of(app).store
    row = store.running_mission(robot_key(services_of(app).gateway))
    return view.as_json(store, row["id"]) if row else None


def palette(app: Any) -> Iterable[SystemCommand]:
    """The commands that apply to the live mission now (none without one)."""
    m = live_mission(app)
    if m is None:
        return
    mission = f"mission {m['id']}"
    if m["status"] == "running" and not m["pause_requested"]:
        yield SystemCommand(
            "Mission: pause",
            f"Hold {mission} at the end of step {m['step']} (p on the Dashboard)",
            partial(control, app, "pause"),
        )
    if m["status"] == "paused" or m["pause_requested"]:
        yield SystemCommand(
            "Mission: resume",
            f"{mission[:1].upper()}{mission[1:]} goes on (p on the Dashboard)",
            partial(control, app, "resume"),
        )
    yield SystemCommand(
        "Mission: cancel",
        f"Cancel {mission} and stop the robot (escape on the Dashboard)",
        partial(control, app, "cancel"),
    )


def control(app: Any, what: str) -> None:
    """pause | resume | toggle | cancel, off the UI thread (the store is written)."""
    app.run_worker(partial(_control, app, what), thread=True, group="mission-control")


def _control(app: Any, what: str) -> None:
    store = services_of(app).store
    m = live_mission(app)
    if m is None:
        app.call_from_thread(app.notify, "no mission is running", title="mission")
        return
    held = m["status"] == "paused" or m["pause_requested"]
    if what == "toggle":
        what = "resume" if held else "pause"
    mission = f"mission {m['id']}"
    if what == "cancel":
        before = store.request_mission_cancel(m["id"])
        said = (
            f"{mission}: cancel asked" if before in ("running", "paused") else f"{mission}: dropped"
        )
    elif what == "pause":
        if m["status"] != "running" or held:
            said = f"{mission} is {m['status']}: nothing to pause"
        else:
            store.request_mission_pause(m["id"])
            said = f"{mission}: pauses at the end of step {m['step']} of {m['steps_total']}"
    elif not held:
        said = f"{mission} is not paused: nothing to resume"
    else:
        store.request_mission_pause(m["id"], pause=False)
        said = f"{mission}: goes on"
    app.call_from_thread(app.notify, said, title="mission", markup=False)

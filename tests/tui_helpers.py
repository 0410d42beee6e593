"""A console built as the CLI builds it, but on a seeded, paused simulator and a temp store."""

import inspect
import time

import pytest

from astiop.app import make_app
from astiop.config import load_settings
from astiop.sim.simulator import Simulator
from astiop.store import Store


def console(tmp_path, model: str = "rules", sim: Simulator | None = None, **kwargs):
    settings = kwargs.pop("settings", {})
    overrides = {"llm": {"model": model}, **settings}
    cfg = load_settings(overrides, env={}, path=tmp_path / "none.toml")
    store = Store(tmp_path / "console.db")
    return make_app(cfg, store, sim=sim or Simulator(seed=0), realtime=False, **kwargs)


def sim_of(app) -> Simulator:
    """The simulator behind the console (tests only: the UI never reaches it)."""
    return app.services.gateway.backend.sim


async def ask(app, pilot, request: str) -> str:
    """Send a request from the Chat screen and wait for the turn: the answers' text."""
    from textual.widgets import Input

    await pilot.press("f2")
    await pilot.pause()
    app.screen.query_one(Input).value = request
    await pilot.press("enter")
    await app.workers.wait_for_complete()
    await pilot.pause()
    return " ".join(str(w.render()) for w in app.screen.query(".answer"))


async def wait_for(pilot, predicate, timeout: float = 30.0, what: str = "") -> None:
    """Until `predicate()` holds, letting the app run between checks (generous: a loaded
    machine is slow, and a passing test waits no longer than it must)."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            if not what:
                try:
                    what = inspect.getsource(predicate).strip()
                except (OSError, TypeError):
                    what = repr(predicate)
            pytest.fail(f"still not so after {timeout:g} s: {what}", pytrace=False)
        await pilot.pause(0.05)

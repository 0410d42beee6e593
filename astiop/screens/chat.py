"""Chat: a request becomes ros2 commands, each shown checked, run and explained."""

from __future__ import annotations

import asyncio
from functools import partial

from rich.text import Text
from textual import work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import VerticalScroll
from textual.widgets import Collapsible, Footer, Header, Input, Static

from astiop.agent.fleet_turn import FleetAgent
from astiop.agent.models.embedded import EmbeddedModelError
from astiop.agent.models.specs import SpecError, open_endpoint
from astiop.agent.turn import Agent, TurnResult
from astiop.bounded import escape_controls
from astiop.screens.base import ConsoleScreen
from astiop.screens.messages import GoalEnded, TurnFinished
from astiop.transports.base import Execution

HELP = (
    "Ask in plain language, e.g. 'what is the battery level?' or 'send the robot to "
    "{where}'.  /model SPEC switches the model, /mode command|tool the reply mode."
)


def help_text(places: list[str]) -> str:
    """The example goal is a place on this robot's map (or coordinates where it has none)."""
    where = "shipping" if "shipping" in places else (places[0] if places else "x 1.0 y 0.5")
    return HELP.format(where=where)


class CommandView(Static):
    def __init__(self, ex: Execution):
        ok = ex.executed and not ex.error
        mark = "✓" if ok else "✗"
        line = Text(f"{mark} {escape_controls(ex.command)}", style="green" if ok else "red")
        why = ex.reason or ex.error
        if why:
            line.append(f"\n  {escape_controls(why)}", style="italic")
        for note in ex.notes:
            line.append(f"\n  note: {note}", style="yellow")
        super().__init__(line, classes="cmd-ok" if ok else "cmd-bad")


class TurnView:
    """One turn in the chat log: its commands and answer go in above its status line."""

    def __init__(self, log: VerticalScroll, status: Static):
        self.log, self.status = log, status
        self.answer = Static("", classes="answer")
        self.parts: list[str] = []

    def _before_status(self, widget) -> None:
        self.log.mount(widget, before=self.status)
        self.log.scroll_end(animate=False)

    def on_event(self, kind: str, data) -> None:
        """The agent's progress. It calls back on the app's loop (its model client streams with
        asyncio; the robot's commands run in threads but are reported after them), so the
        widgets are updated here, in order, and are complete when the turn returns."""
        if kind == "command":
            self.command_executed(data)
        elif kind == "status":
            self.status.update(Text(str(data), style="dim"))
        elif kind == "answer_token":
            if not self.parts:
                self._before_status(self.answer)
            self.parts.append(str(data))
            # dim until the turn ends: the shown answer is the checked one, not this stream
            self.answer.update(Text(escape_controls("".join(self.parts)), style="dim italic"))

    def command_executed(self, ex: Execution) -> None:
        self._before_status(CommandView(ex))
        if ex.output:
            out = Static(Text(escape_controls(ex.output.rstrip())))
            self._before_status(Collapsible(out, title="output", collapsed=True))

    def show(self, result: TurnResult) -> None:
        if not self.parts:
            self._before_status(self.answer)
        self.answer.update(Text(escape_controls(result.answer)))  # checked, not the stream
        if result.grounding.startswith("replaced"):
            why = result.grounding.removeprefix("replaced: ")
            note = Text(f"⚠ answer built from the results: the model's reply was not used ({why})")
            note.stylize("yellow italic")
            self._before_status(Static(note, classes="grounding"))
        elif result.grounding.startswith("kept, "):
            dropped = result.grounding.removeprefix("kept, ")
            note = Text(f"⚠ the model's words, checked: {dropped} (not what the robot reported)")
            note.stylize("yellow italic")
            self._before_status(Static(note, classes="grounding"))
        if result.refused:
            self._before_status(Static(Text("⛔ refused by the intent gate", style="red")))
        info = f"{result.model} · {result.mode} · {result.total_s:.1f} s"
        if result.completion_tokens:
            info += f" · {result.completion_tokens} tokens"
        if result.error:
            info += f" · {result.error}"
        self.status.update(Text(info, style="dim red" if result.error else "dim"))
        self.log.scroll_end(animate=False)


class ChatScreen(ConsoleScreen):
    BINDINGS = [Binding("escape", "cancel", "Cancel reply")]

    def compose(self) -> ComposeResult:
        yield Header(show_clock=False)
        places = [loc.name for loc in self.services.store.list_locations()]
        yield VerticalScroll(Static(help_text(places), classes="answer"), id="chat-log")
        yield Input(
            placeholder="Ask the robot…  (/model SPEC, /mode command|tool)", id="chat-input"
        )
        yield Footer()

    def on_mount(self) -> None:
        self._turn_lock = asyncio.Lock()
        self._reply_mode: str | None = None  # /mode: for the agents made after it too
        services = self.services
        self.agent = self._agent_for(services.gateway)
        fleet = self.app.fleet
        if fleet is not None:  # a request names its robot, else it is the current one's
            self.agent = FleetAgent(
                self._robot_agent,
                lambda: self.app.current_robot,
                fleet.rows,
                lambda: {loc.name: (loc.x, loc.y) for loc in services.store.list_locations()},
                services.store,
                session="console",
            )
        self.query_one(Input).focus()

    def _agent_for(self, gateway, robot: str = "") -> Agent:
        services, safety = self.services, self.app.safety  # the operator's approvals
        return Agent(
            gateway,
            services.endpoint,
            services.store,
            mode=self._reply_mode or services.settings.llm.mode,
            max_tokens=services.settings.llm.max_tokens,
            confirm=partial(safety.confirm_from_thread, robot=robot),
            confirm_mission=safety.confirm_mission_from_thread,
            replace_mission=safety.replace_mission_from_thread,
            confirm_reaction=safety.confirm_reaction_from_thread,
            session="console",
            robot=robot,
        )

    def _robot_agent(self, name: str) -> Agent:
        """A robot of the fleet's own agent, made the first time a request is about it (its
        first motion takes its control if no one holds it)."""
        agents = self.__dict__.setdefault("_agents", {})
        if name not in agents:
            gateway = self.app.fleet.gateway_of(name)
            if gateway is None:
                raise LookupError(f"{name} is not reached yet: nothing was sent to it")
            agents[name] = self._agent_for(gateway, name)
        return agents[name]

    def _log(self, widget) -> None:
        log = self.query_one("#chat-log", VerticalScroll)
        log.mount(widget)
        log.scroll_end(animate=False)

    def on_input_submitted(self, event: Input.Submitted) -> None:
        text = event.value.strip()
        event.input.value = ""
        if not text:
            return
        if text.startswith("/model"):
            self.switch_model(text.removeprefix("/model").strip())
        elif text.startswith("/mode"):
            self.switch_reply_mode(text.removeprefix("/mode").strip())
        else:
            self._log(Static(Text(f"you: {escape_controls(text)}"), classes="user-msg"))
            self.run_turn(text)

    def switch_reply_mode(self, mode: str) -> None:
        if mode not in ("command", "tool"):
            self.notify("/mode takes 'command' or 'tool'", severity="error", markup=False)
            return
        self.agent.switch(mode=mode)  # the conversation goes on
        self._reply_mode = mode
        self.notify(f"reply mode: {mode}")

    def switch_model(self, spec: str) -> None:
        try:
            spec = spec or "rules"
            endpoint = open_endpoint(spec, vision=self.services.settings.llm.marks_vision(spec))
        except SpecError as exc:
            self.notify(str(exc), severity="error", markup=False)
            return
        old = self.services.endpoint
        self.services.endpoint = endpoint
        self.agent.switch(
            endpoint,
            self.agent.mode if self.agent.mode != "rules" else self.services.settings.llm.mode,
        )
        self.app.refresh_subtitle()
        self.run_worker(old.close, thread=True, group="model")
        self.notify(f"model: {endpoint.spec.raw}", markup=False)

    @work(group="llm", exit_on_error=False)
    async def run_turn(self, text: str) -> None:
        """One turn at a time, in the order asked: a request sent during a turn waits for it
        (escape cancels the turn and every request waiting)."""
        waiting = self._turn_lock.locked()
        status = Static(
            Text("waiting for the turn before it…" if waiting else "thinking…", style="dim"),
            classes="answer",
        )
        self._log(status)
        try:
            async with self._turn_lock:
                status.update(Text("thinking…", style="dim"))
                view = TurnView(self.query_one("#chat-log", VerticalScroll), status)
                try:
                    result: TurnResult = await self.agent.turn(text, view.on_event)
                except EmbeddedModelError as exc:
                    status.update(Text(str(exc), style="red"))
                    return
                view.show(result)  # here, once; the broadcast is for the other screens
                if result.started:
                    self.follow(result)
                self.app.post_message(TurnFinished(result, result.model))
        except asyncio.CancelledError:
            status.update(Text("canceled: nothing more was sent for this request", style="red"))
            raise

    @work(group="follow", exit_on_error=False)
    async def follow(self, result: TurnResult) -> None:
        text = await self.agent.follow_up(result)
        self.post_message(GoalEnded(result, text))

    def on_goal_ended(self, msg: GoalEnded) -> None:
        ok = msg.result.outcome == "succeeded"
        line = Text(f"↳ {msg.text}   (for: {msg.result.prompt})")
        line.stylize("green" if ok else "yellow")
        self._log(Static(line, classes="follow-up"))

    def action_cancel(self) -> None:
        cancelled = self.workers.cancel_group(self, "llm")
        if cancelled:
            self.notify("reply cancelled")

"""`astiop chat`: one request through the agent, headless, as the console's Chat does."""

from __future__ import annotations

import asyncio

import typer

from astiop.cli.common import Ending, fail, interactive, print_json, state, take_control
from astiop.cli.mission_follow import follow_mission


def _robot_named(st, text: str, as_json: bool) -> str | None:
    """A fleet and no --robot-name: the request goes to the robot it names (its name, its
    number, the one at a place, the nearest idle one to a place), said to it as "the robot";
    a question about the whole fleet is answered here from every robot's row (None)."""
    from astiop.agent.fleet_words import FleetWordsError, addressed, fleet_answer, fleet_question
    from astiop.cli.fleet import members, read_rows
    from astiop.robot.fleet import is_fleet
    from astiop.robot.fleet_watch import FleetRow

    if st.robot_name is not None or not is_fleet(st.fleet_settings):
        return text
    robots = members(st)
    asked = fleet_question(text)
    if asked is not None:
        answer = fleet_answer(asked, read_rows(st, robots))
        if as_json:
            print_json({"answer": answer})
        else:
            typer.echo(answer)
        return None
    places = {loc.name: (loc.x, loc.y) for loc in st.store.list_locations()}
    try:  # by its name or number first: no robot need be read for that
        to = addressed(text, [FleetRow(r.name, r.namespace) for r in robots], places)
    except FleetWordsError:
        to = None
    try:
        to = (
            to
            if to is not None and to.how == "as named"
            else addressed(text, read_rows(st, robots), places)
        )
    except FleetWordsError as exc:
        fail(str(exc))
    if to is None:
        names = ", ".join(r.name for r in robots)
        fail(f"which robot? this request names none of the fleet's ({names}): name one, "
             "or give --robot-name")  # fmt: skip
    if not as_json:
        typer.echo(f"to {to.name} ({to.how})", err=True)
    st.address(to.name)
    return to.request


def chat(
    ctx: typer.Context,
    text: str = typer.Argument(..., help="What you want, in plain language."),
    model: str = typer.Option(None, "--model", "-m", help="Model spec (default: settings)."),
    mode: str = typer.Option(None, "--mode", help="command (model writes ros2 lines) or tool."),
    yes: bool = typer.Option(False, "--yes", "-y", help="Do not ask before moving the robot."),
    wait: bool = typer.Option(
        True,
        "--wait/--no-wait",
        help="Wait for a goal the turn started to end, and report how (default: wait).",
    ),
    interpretation: str = typer.Option(
        "grounded",
        "--interpretation",
        help="grounded (answers checked against the results) or raw (the model's text).",
    ),
    replace: bool = typer.Option(
        False,
        "--replace",
        help="A mission while another runs on the robot replaces it (default: refused).",
    ),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Run one agent turn against the robot (the simulator by default) and print the answer."""
    from astiop.agent.models.embedded import EmbeddedModelError
    from astiop.agent.models.specs import SpecError, open_endpoint

    st = state(ctx)
    text = _robot_named(st, text, as_json)
    if text is None:
        return  # a question about the whole fleet, answered
    settings = st.settings
    mode = mode or settings.llm.mode
    if mode not in ("command", "tool"):
        fail(f"--mode must be 'command' or 'tool', not '{mode}'")
    if interpretation not in ("grounded", "raw"):
        fail(f"--interpretation must be 'grounded' or 'raw', not '{interpretation}'")
    try:
        endpoint = open_endpoint(
            model or settings.llm.model,
            threads=settings.llm.threads,
            n_ctx=settings.llm.context,
            timeout_s=settings.llm.timeout_s,
            vision=settings.llm.marks_vision(model or settings.llm.model),
        )
        endpoint.launch()  # the model loads while the robot starts
    except (SpecError, EmbeddedModelError) as exc:
        fail(str(exc))
    from astiop.agent.turn import Agent
    from astiop.robot.factory import make_robot_gateway
    from astiop.transports.base import BackendError

    try:
        gateway = make_robot_gateway(settings, st.store)
    except BackendError as exc:
        endpoint.close(wait_s=0)  # the model's process ends on its own
        fail(str(exc))
    take_control(gateway, st)

    def ask(checked) -> bool:
        return typer.confirm(f"run '{checked.command.display()}' (it moves the robot)?", err=True)

    confirm = (lambda _c: True) if yes else (ask if interactive() else None)

    def ask_mission(steps, forever: bool = False) -> bool:
        from astiop.missions.steps import describe

        plan = describe(steps, forever)
        return typer.confirm(f"run this mission (it moves the robot)? {plan}", err=True)

    confirm_mission = (
        (lambda _s, _f=False: True) if yes else (ask_mission if interactive() else None)
    )

    def ask_reaction(question: str) -> bool:
        return typer.confirm(question, err=True)

    confirm_reaction = (lambda _q: True) if yes else (ask_reaction if interactive() else None)

    def on_step(report) -> None:
        if not as_json:
            typer.echo(report.line(), err=True)

    from astiop.missions.runner import MissionRunner

    def on_note(text: str) -> None:
        if not as_json:
            typer.echo(text, err=True)

    runner = MissionRunner(gateway, st.store, on_step=on_step, on_note=on_note)
    runner.queue_only = not wait  # --no-wait: a process of its own drives the mission
    agent = Agent(
        gateway,
        endpoint,
        st.store,
        mode=mode,
        max_tokens=settings.llm.max_tokens,
        confirm=confirm,
        session="cli",
        interpretation=interpretation,
        missions=runner,
        confirm_mission=confirm_mission,
        replace_mission=replace,
        confirm_reaction=confirm_reaction,
    )

    streamed = []  # whether the answer came as tokens (a model's, the rules'), or whole

    def on_event(kind: str, data) -> None:
        if as_json:
            return
        if kind.startswith("answer"):
            streamed.append(kind)
        if kind == "command":
            mark = "ran" if data.executed else "REJECTED"
            typer.echo(
                f"[{mark}] {data.command}" + (f" — {data.reason}" if data.reason else ""), err=True
            )
        elif kind == "answer_token":
            typer.echo(data, nl=False)
        elif kind == "answer_trimmed":
            typer.echo("\n[checked] what the robot's results do not support was dropped:", err=True)
            typer.echo(data, nl=False)
        elif kind == "answer_replaced":
            typer.echo("\n[checked] the model's reply was not used; from the results:", err=True)
            typer.echo(data, nl=False)
        elif kind == "status":
            typer.echo(f"... {data}", err=True)

    async def turn_and_follow():
        result = await agent.turn(text, on_event)
        follow = ""
        if result.mission_id is not None:
            if not as_json:
                typer.echo("", err=True)
            if wait:
                follow = await asyncio.to_thread(follow_mission, runner, result.mission_id)
            else:
                from astiop.cli.mission import drive_detached

                log = drive_detached(st, result.mission_id)
                follow = (
                    f"mission {result.mission_id} is driven by a process of its own "
                    f"(astiop mission show {result.mission_id}; its log: {log})"
                )
        elif result.started and wait:
            if not as_json:
                typer.echo(f"\n... {result.started}; waiting for it to end", err=True)
            gateway.start()  # the robot's state, to see how the goal ends
            follow = await agent.follow_up(result)
        return result, follow

    try:
        result, follow = asyncio.run(turn_and_follow())
    except EmbeddedModelError as exc:
        fail(str(exc))
    finally:
        endpoint.close(wait_s=0)  # the model's process ends on its own
    gateway.close()
    st.store.close()
    if as_json:
        print_json({**result.as_json(), "follow_up": follow or None})
    else:
        if not streamed and result.answer:  # answered without the model: said whole
            typer.echo(result.answer, nl=False)
        typer.echo("")
        if follow:
            typer.echo(f"↳ {follow}")
        if result.error:
            typer.echo(f"astiop: {result.error}", err=True)
    # all is written and closed; a ROS 2 node still leaves the robot's graph at exit (rclpy's
    # shutdown, run at exit): without it the robot would list this process for a while
    Ending.at_once = settings.robot.backend != "ros2"
    if result.error:
        raise typer.Exit(1)

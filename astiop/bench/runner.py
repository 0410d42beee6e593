"""Runs a benchmark: models × modes × cases, each result stored as it finishes.

An interrupted run keeps what it finished; `resume` picks up the cases still missing. The
same seed gives the same simulator set-ups and the same sampling seed for the models.
"""

from __future__ import annotations

import asyncio
import json
import re
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

from astiop.agent.models.llm import LLMError, LLMTimeout
from astiop.agent.models.specs import LLMEndpoint, open_endpoint, parse_spec
from astiop.bench import library, multistep, paper_protocol, questions, stage1, stage2
from astiop.bench.case_turn import case_agent, scored
from astiop.bench.live import close_live, live_case
from astiop.bench.suites import SuiteError
from astiop.config import Settings
from astiop.recording import FLUSH_S, SessionRecorder
from astiop.robot.factory import make_safety
from astiop.robot.gateway import RobotGateway
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend


@dataclass
class RunConfig:
    stage: int
    models: list[str]
    modes: list[str] = field(default_factory=lambda: ["tool"])
    limit: int | None = None
    seed: int = 0
    timeout_s: float = 120.0
    max_tokens: int = 384
    concurrency: int = 1
    interpretation: str = "grounded"  # or raw: the model's words, as the paper scores them
    record_dir: str | None = None  # stage 2: each case's simulator run as MCAP here
    protocol: str = "astiop"  # astiop | paper | both (stage 1): how cases are run and scored
    suite: str | None = None  # a suite's name or path; None: the built-in one of the stage
    robot: str = "sim"  # stage 2: sim (a seeded simulator per case) or ros2 (the live robot)


@dataclass(frozen=True)
class Progress:
    done: int
    total: int
    model: str
    mode: str
    case_id: str
    outcome: str
    elapsed_s: float

    @property
    def eta_s(self) -> float:
        return self.elapsed_s / self.done * (self.total - self.done) if self.done else 0.0


class BenchError(ValueError):
    pass


PROTOCOLS = ("astiop", "paper", "both")


def create_run(store: Store, config: RunConfig) -> int:
    if config.stage not in (1, 2):
        raise BenchError("--stage is 1 or 2")
    suite_of(store, config)  # a one-line error now, not after the first model loads
    return store.create_bench_run(config.stage, asdict(config))


def suite_of(store: Store, config: RunConfig) -> library.Suite:
    """The run's suite, checked against its stage and protocol."""
    if config.protocol not in PROTOCOLS:
        raise BenchError(f"--protocol is {', '.join(PROTOCOLS)}")
    try:
        suite = library.load_suite(config.suite or f"astiop-stage{config.stage}", store.path.parent)
    except SuiteError as exc:
        raise BenchError(str(exc)) from None
    if suite.stage != config.stage:
        raise BenchError(
            f"suite {suite.name} is a stage-{suite.stage} suite, not stage {config.stage}"
        )
    if config.stage == 2 and config.protocol == "both":
        raise BenchError(
            "--protocol both is for stage 1: stage 2's protocols run different suites "
            "(astiop's on the simulator, the paper's on mock responses)"
        )
    if suite.kind == "mock" and config.protocol != "paper":
        raise BenchError(
            f"suite {suite.name} answers fixed mock responses: run it with --protocol paper"
        )
    if suite.kind == "robot" and config.protocol != "astiop":
        raise BenchError(
            f"the paper's protocol answers mock responses, and suite {suite.name} has none: "
            "import the paper's stage-2 script (astiop bench import) and use --suite paper-stage2"
        )
    if config.protocol == "paper":  # with both, the rules baseline runs astiop's protocol
        for model in config.models:
            if parse_spec(model).kind == "rules":
                raise BenchError("the paper's protocol measures a model server; rules has none")
    return suite


def modes_for(config: RunConfig, model: str) -> list[str]:
    """What each model runs as: its reply modes (astiop), `paper`, or both for stage 1."""
    if parse_spec(model).kind == "rules":
        return ["rules"]
    if config.stage == 1:
        return {"astiop": ["chat"], "paper": ["paper"], "both": ["chat", "paper"]}[config.protocol]
    return ["paper"] if config.protocol == "paper" else config.modes


def load_config(store: Store, run_id: int) -> RunConfig:
    run = store.bench_run(run_id)
    if run is None:
        raise BenchError(f"there is no benchmark run {run_id} (astiop bench list shows them)")
    return RunConfig(**json.loads(run["config"]))


def _done(store: Store, run_id: int) -> set[tuple[str, str, str]]:
    return {(r["model"], r["mode"], r["case_id"]) for r in store.bench_results(run_id)}


def _save(
    store: Store,
    run_id: int,
    model: str,
    mode: str,
    case,
    outcome: str,
    metrics: dict,
    response: str,
) -> None:
    store.add_bench_result(
        run_id,
        {
            "model": model,
            "mode": mode,
            "case_id": case.id,
            "level": case.level,
            "category": case.category,
            "outcome": outcome,
            "metrics": json.dumps(
                {"prompt": getattr(case, "prompt", None) or case.request, **metrics}, default=str
            ),
            "response": response,
        },
    )


async def run(
    store: Store,
    settings: Settings,
    config: RunConfig,
    run_id: int,
    on_progress: Callable[[Progress], None] | None = None,
) -> int:
    """Run (or resume) `run_id`; returns how many cases ran now."""
    suite = suite_of(store, config)
    cases = list(suite.cases)[: config.limit or None]
    done = _done(store, run_id)
    todo = [
        (m, mode, c)
        for m in config.models
        for mode in modes_for(config, m)
        for c in cases
        if (m, mode, c.id) not in done
    ]
    finished = 0
    status = "interrupted"
    with tempfile.TemporaryDirectory(prefix="astiop-bench-") as tmp:
        # the cases' world: on the simulator, the named locations seeded from data/ (never the
        # operator's tables); on a live robot, the operator's places of its map (copied: the
        # run never changes them)
        world = Store(Path(tmp) / "world.db")
        if config.robot == "ros2":
            world.copy_locations_from(store)
        try:
            finished = await _run_todo(
                store, world, settings, config, run_id, suite, todo, on_progress
            )
            status = "done"
        finally:
            close_live(world)
            world.close()
            store.end_bench_run(run_id, status)
    return finished


async def _run_todo(store, world, settings, config, run_id, suite, todo, on_progress) -> int:
    total, finished, t0 = len(todo), 0, time.perf_counter()
    models = list(dict.fromkeys(m for m, _, _ in todo))
    for model in models:
        endpoint = open_endpoint(
            model,
            threads=settings.llm.threads,
            n_ctx=settings.llm.context,
            timeout_s=config.timeout_s,
        )
        try:
            for mode in dict.fromkeys(md for m, md, _ in todo if m == model):
                batch = [c for m, md, c in todo if m == model and md == mode]
                # the scripts run in turn; a live robot takes one case at a time
                one_at_a_time = endpoint.local or mode == "paper" or config.robot == "ros2"
                sem = asyncio.Semaphore(1 if one_at_a_time else max(1, config.concurrency))

                async def one(case, mode=mode, endpoint=endpoint, model=model, sem=sem):
                    nonlocal finished
                    async with sem:
                        outcome, metrics, response = await _run_case(
                            world, settings, config, endpoint, suite, case, mode, (run_id, model)
                        )
                    await asyncio.to_thread(
                        _save, store, run_id, model, mode, case, outcome, metrics, response
                    )
                    finished += 1
                    if on_progress:
                        on_progress(
                            Progress(
                                finished,
                                total,
                                model,
                                mode,
                                case.id,
                                outcome,
                                time.perf_counter() - t0,
                            )
                        )

                await asyncio.gather(*(one(c) for c in batch))
        finally:
            endpoint.close()
    return finished


async def _run_case(world, settings, config, endpoint: LLMEndpoint, suite, case, mode, who):
    if mode == "paper":  # its own timeouts (300 s, 120 s a call), as the scripts set them
        url, model = await asyncio.to_thread(endpoint.completions)
        if config.stage == 1:
            return await paper_protocol.stage1_case(url, model, suite.system, case)
        return await paper_protocol.stage2_case(url, model, suite, case)
    try:
        if config.stage == 1:
            return await asyncio.wait_for(
                stage1.run_case(endpoint, suite.system, case, config.max_tokens), config.timeout_s
            )
        if config.robot == "ros2":  # driving to the case's start takes the robot's own time
            return await _robot_case(world, settings, config, endpoint, case, mode, who)
        return await asyncio.wait_for(
            _robot_case(world, settings, config, endpoint, case, mode, who), config.timeout_s
        )
    except (asyncio.TimeoutError, LLMTimeout):
        return "timeout", {"total_s": config.timeout_s}, ""
    except LLMError as exc:
        return "error", {"total_s": 0.0}, str(exc)


async def _robot_case(store, settings, config, endpoint, case, mode, who):
    """One request against a seeded simulator; `store` is the run's own world (locations)."""
    if config.robot == "ros2":
        return await live_case(store, settings, config, endpoint, case, mode)
    sim = stage2.build_sim(case, store, config.seed)
    gateway = RobotGateway(SimBackend(sim, store), make_safety(settings, store))
    recorder = _case_recorder(config, gateway, sim, case, mode, who)
    try:
        return await _drive_case(store, config, endpoint, case, mode, sim, gateway)
    finally:
        if recorder is not None:
            sim.after_step.remove(recorder.poll)
            await asyncio.to_thread(recorder.stop)


def _case_recorder(config, gateway, sim, case, mode, who):
    """A recorder polled after every simulator step, when the run records (--record DIR)."""
    if not config.record_dir:
        return None
    run_id, model = who
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", f"run{run_id}-{model}-{mode}-{case.id}")
    recorder = SessionRecorder(Path(config.record_dir) / f"{name}.mcap", gateway, flush_s=FLUSH_S)
    sim.after_step.append(recorder.poll)
    return recorder


async def _drive_case(store, config, endpoint, case, mode, sim, gateway):
    if "visits" in case.outcome:  # a multi-step case: run as a mission, scored by order
        agent = multistep.mission_agent(store, config, endpoint, mode, gateway, case)
        return await multistep.drive(store, case, agent, sim)
    agent = case_agent(store, config, endpoint, mode, gateway)
    turn = await agent.turn(case.request)
    if questions.is_questions(case):  # a question: right, honestly declined, or else
        return questions.scored(case, turn)
    truth = stage2.Truth.of_sim(sim)
    if sim.goal is not None:
        await asyncio.to_thread(sim.run_goal, 600.0)
    await asyncio.to_thread(sim.run_until, lambda: False, 5.0)  # a conveyor transfer ends
    return scored(case, turn, truth, stage2.Truth.of_sim(sim), store)

"""The embedded model: a real llama.cpp server (xllamacpp) with SmolLM2-135M on 127.0.0.1."""

import json
import subprocess
import sys
import time

import httpx
import pytest

from astiop.agent.facts import facts_of
from astiop.agent.models.embedded import EmbeddedModelError, EmbeddedServer, smollm2_path
from astiop.agent.models.llm import OpenAIClient
from astiop.agent.models.specs import LLMEndpoint, parse_spec
from astiop.agent.turn import Agent
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.transports.simulator.backend import SimBackend

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("embedded")]  # one server


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    cache_dir = tmp_path_factory.mktemp("prompt-cache")  # not the user's cache folder
    s = EmbeddedServer(smollm2_path(), threads=1, n_ctx=2048, cache_dir=cache_dir).start()
    yield s
    s.stop()


@pytest.fixture(scope="module")
def endpoint(server):
    ep = LLMEndpoint(parse_spec("embedded"), threads=1, n_ctx=2048)
    ep.server = server  # share the one server across the module
    ep._client = server.client()  # each kind of call pinned to its slot
    return ep


def test_health_and_models(server):
    assert httpx.get(f"http://127.0.0.1:{server.port}/health").status_code == 200
    assert server.startup_s < 30


def test_non_streaming_reply_carries_usage_and_timings(server):
    body = {"messages": [{"role": "user", "content": "Say hello."}], "max_tokens": 8}
    data = httpx.post(f"{server.base_url}/chat/completions", json=body, timeout=60).json()
    assert data["choices"][0]["message"]["content"]
    assert data["usage"]["completion_tokens"] > 0 and data["timings"]["predicted_n"] > 0


async def test_streaming_with_usage(server):
    client = OpenAIClient(server.base_url, server.model_name)
    pieces = []
    c = await client.chat(
        [{"role": "user", "content": "Name a colour."}], max_tokens=12, on_token=pieces.append
    )
    assert len(pieces) >= 2 and "".join(pieces) == c.text
    assert c.prompt_tokens and c.completion_tokens and c.tokens_per_s > 1
    assert c.ttft_s < c.total_s


async def test_json_schema_reply_validates(server):
    schema = {
        "type": "object",
        "properties": {"level": {"enum": ["low", "high"]}},
        "required": ["level"],
    }
    client = OpenAIClient(server.base_url, server.model_name)
    c = await client.chat(
        [{"role": "user", "content": "Is 90% battery low or high?"}], schema=schema, max_tokens=64
    )
    assert json.loads(c.text)["level"] in ("low", "high")


def make_agent(endpoint, store, interpret_tokens=8):
    # These check the plan; a short interpretation (replaced by the results when cut) saves CPU.
    gateway = RobotGateway(SimBackend(Simulator(seed=0), store), SafetyPolicy())
    return Agent(
        gateway,
        endpoint,
        store,
        mode="tool",
        max_tokens=96,
        confirm=lambda c: True,
        interpret_tokens=interpret_tokens,
    )


async def test_agent_reads_the_battery(endpoint, store):
    result = await make_agent(endpoint, store).turn("What is the battery level?")
    assert [c.command for c in result.commands] == ["ros2 topic echo /battery_status --once"]
    assert result.commands[0].executed and result.answer


async def test_agent_reads_the_position(endpoint, store):
    result = await make_agent(endpoint, store).turn("Where is the robot right now?")
    assert [c.command for c in result.commands] == ["ros2 topic echo /robot_pose --once"]


async def test_agent_sends_the_robot_to_a_named_location(endpoint, store):
    agent = make_agent(endpoint, store)
    result = await agent.turn("Send the robot to the assembly station")
    assert result.commands and result.commands[0].values["success"] is True
    sim = agent.gateway.backend.sim
    outcome = sim.run_goal(300)
    assert outcome.status == "succeeded" and outcome.name == "assembly_station"
    assert abs(sim.pose[0] - 8.0) < 0.1 and abs(sim.pose[1] - 22.6) < 0.1


async def test_every_narrowed_tool_grammar_is_one_llama_cpp_parses(endpoint, store):
    """The grammar offers only the tools of the request's intent; each variant must parse."""
    agent = make_agent(endpoint, store)
    result = await agent.turn("Leave the dock")
    assert [c.command for c in result.commands] == [
        "ros2 service call /undock std_srvs/srv/Trigger"
    ]
    result = await agent.turn("Save this spot as bay_9")  # last: a new place changes the prompt
    assert result.commands and result.commands[0].command.startswith(
        "ros2 service call /save_location"
    )
    assert "bay" in result.commands[0].command and result.commands[0].values["success"] is True


async def test_a_grounded_answer_states_only_what_the_robot_reported(endpoint, store):
    from astiop.agent import grounding

    result = await make_agent(endpoint, store, 96).turn("is anything blocking the robot?")
    facts = facts_of(result.prompt, result.commands)
    assert result.grounding in ("kept",) or result.grounding.startswith("replaced: ")
    assert grounding.unsupported(result.answer, facts) is None
    assert grounding.missing(result.answer, result.commands) is None


def health(port: int) -> int:
    return httpx.get(f"http://127.0.0.1:{port}/health", timeout=2).status_code


def test_the_model_serves_from_its_own_process_until_stopped():
    s = EmbeddedServer(smollm2_path(), threads=1, n_ctx=512, prompt_cache=False).launch()
    try:
        assert s.start().startup_s < 30 and health(s.port) == 200
    finally:
        s.stop()
    with pytest.raises(httpx.HTTPError):
        health(s.port)


def test_the_model_stops_when_the_process_that_started_it_is_killed():
    code = (
        "import sys; from astiop.agent.models.embedded import EmbeddedServer, smollm2_path; "
        "s = EmbeddedServer(smollm2_path(), threads=1, n_ctx=512, prompt_cache=False).start(); "
        "print(s.port, flush=True); sys.stdin.read()"
    )
    parent = subprocess.Popen(
        [sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        port = int(parent.stdout.readline())
        assert health(port) == 200
    finally:
        parent.kill()  # no stop(), no cleanup of any kind
        parent.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            health(port)
        except httpx.HTTPError:
            return
        time.sleep(0.1)
    pytest.fail(f"the model still serves on port {port} 10 s after its parent was killed")


def test_a_file_that_is_no_model_is_a_one_line_error(tmp_path):
    bad = tmp_path / "bad.gguf"
    bad.write_bytes(b"GGUF" + bytes(64))
    with pytest.raises(EmbeddedModelError, match="the embedded model") as info:
        EmbeddedServer(bad, threads=1, n_ctx=512, prompt_cache=False).start(ready_timeout_s=30)
    assert "\n" not in str(info.value)


def test_a_model_process_started_ahead_is_the_one_that_serves():
    from astiop.agent.models import model_spawn

    model_spawn.start_ahead()  # as `astiop chat` does before its imports
    ahead = model_spawn._ahead
    try:
        s = EmbeddedServer(smollm2_path(), threads=1, n_ctx=512, prompt_cache=False).start()
    finally:
        model_spawn.discard_ahead()  # none left for another test in this worker
    try:
        assert s._proc is ahead and health(s.port) == 200
    finally:
        s.stop()
    assert ahead.poll() is not None

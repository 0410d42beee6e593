"""The LLM clients over real HTTP against scripted servers on 127.0.0.1."""

import socket
import time

import pytest

from astiop.agent.models.llm import (
    LLMHTTPError,
    LLMProtocolError,
    LLMTimeout,
    LLMUnavailable,
    OllamaClient,
    OpenAIClient,
)
from tests.scripted_llm import ScriptedLLM


@pytest.fixture(params=["openai", "ollama"])
def server(request):
    s = ScriptedLLM(request.param)
    yield s
    s.close()


def client_for(server, timeout_s=10.0):
    cls = OpenAIClient if server.flavour == "openai" else OllamaClient
    return cls(server.url, "scripted", timeout_s=timeout_s)


async def test_streams_tokens_and_reports_usage(server):
    server.default = "The battery is at 85 percent."
    seen = []
    c = await client_for(server).chat([{"role": "user", "content": "hi"}], on_token=seen.append)
    assert "".join(seen) == c.text == "The battery is at 85 percent."
    assert len(seen) > 3 and c.finish_reason == "stop"
    assert c.ttft_s is not None and 0 < c.ttft_s <= c.total_s
    assert c.completion_tokens == len(seen)
    body = server.requests[0]
    assert body["stream"] is True
    if server.flavour == "openai":
        assert body["stream_options"] == {"include_usage": True}
        assert c.prompt_tokens == 42 and c.cached_tokens == 2
    else:
        assert c.prompt_tokens == 30  # 50 evaluated minus 20 served from cache
        assert c.tokens_per_s == pytest.approx(len(seen) / 0.25)


async def test_llama_server_timings_give_tokens_per_second():
    s = ScriptedLLM("openai")
    s.timings = True
    s.default = "abcdefghijkl"
    try:
        c = await OpenAIClient(s.url, "m").chat([{"role": "user", "content": "x"}])
    finally:
        s.close()
    assert c.tokens_per_s == pytest.approx(4 / 0.5)


async def test_schema_and_grammar_are_sent():
    s = ScriptedLLM("openai")
    try:
        cl = OpenAIClient(s.url, "m")
        await cl.chat([{"role": "user", "content": "x"}], schema={"type": "object"})
        await cl.chat(
            [{"role": "user", "content": "x"}], schema={"type": "object"}, grammar='root ::= "a"'
        )
    finally:
        s.close()
    assert s.requests[0]["response_format"]["json_schema"]["schema"] == {"type": "object"}
    assert s.requests[1]["grammar"] == 'root ::= "a"' and "response_format" not in s.requests[1]


async def test_refused_connection_retries_once_then_fails():
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    cl = OpenAIClient(f"http://127.0.0.1:{port}/v1", "m", connect_timeout_s=1.0)
    t0 = time.perf_counter()
    with pytest.raises(LLMUnavailable) as info:
        await cl.chat([{"role": "user", "content": "x"}])
    assert time.perf_counter() - t0 >= 0.5  # one backoff, one retry
    assert "\n" not in str(info.value) and "cannot connect" in str(info.value)


async def test_slow_server_times_out(server):
    server.mode, server.delay_s = "slow", 2.0
    with pytest.raises(LLMTimeout, match="no answer within 0.5 s"):
        await client_for(server, timeout_s=0.5).chat([{"role": "user", "content": "x"}])


async def test_garbage_stream(server):
    server.mode = "garbage"
    with pytest.raises(LLMProtocolError, match="malformed JSON"):
        await client_for(server).chat([{"role": "user", "content": "x"}])


async def test_http_500_is_one_line(server):
    server.mode = "http500"
    with pytest.raises(LLMHTTPError) as info:
        await client_for(server).chat([{"role": "user", "content": "x"}])
    assert info.value.status == 500 and "\n" not in str(info.value)


async def test_truncated_stream(server):
    server.mode = "truncated"
    server.default = "a reply that will be cut in half"
    with pytest.raises(LLMProtocolError):
        await client_for(server).chat([{"role": "user", "content": "x"}])


async def test_list_models(server):
    models = await client_for(server).list_models()
    assert [m.name for m in models] == (
        ["scripted-model"] if server.flavour == "openai" else ["scripted:1b"]
    )

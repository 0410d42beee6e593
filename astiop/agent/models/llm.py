"""Streaming chat clients over httpx: OpenAI-compatible servers and Ollama's native API.

Every call yields text as it arrives and ends with a `Completion` carrying time to first token
(first non-empty content, measured here), total time, token counts and tokens/s.
"""

from __future__ import annotations

import asyncio
import functools
import json
import ssl
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any, Protocol

import httpx

from astiop.agent.models.reply_stream import Completion, StreamState
from astiop.bounded import one_line

# a message's content is its text, or (a question sent an image) OpenAI's content parts:
# [{"type": "text", "text": ...}, {"type": "image_url", "image_url": {"url": "data:..."}}]
Messages = list[dict[str, Any]]
OnToken = Callable[[str], None]


class LLMError(Exception):
    """A one-line reason the model could not answer; `partial` holds any text streamed first."""

    partial: str = ""


class LLMUnavailable(LLMError):
    pass


class LLMTimeout(LLMError):
    pass


class LLMHTTPError(LLMError):
    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


class LLMProtocolError(LLMError):
    pass


@dataclass(frozen=True)
class _Options:
    max_tokens: int
    temperature: float
    schema: dict | None
    seed: int | None
    grammar: str | None
    guard: bool = False  # cut a reply that repeats itself or runs past its cap or deadline
    penalties: bool = False  # llama.cpp's repeat and DRY penalties
    deadline_s: float | None = None
    slot: int | None = None  # llama.cpp's server slot that keeps this kind of call's prefix


class SlotRouter(Protocol):
    """Pins each kind of call to a server slot of its own (`prompt_cache.PromptCache`)."""

    async def slot_for(self, messages: Messages) -> int | None: ...

    async def kept(self, slot: int, messages: Messages) -> None: ...


@functools.cache
def _with_ca() -> ssl.SSLContext:
    return httpx.create_ssl_context()


@functools.cache
def _without_ca() -> ssl.SSLContext:
    return ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)


def tls_for(url: str) -> ssl.SSLContext:
    """The TLS context for a client of `url`, made once per process: httpx loads the CA bundle
    for every client it builds (25-50 ms each). Plain http (the embedded server on 127.0.0.1)
    never needs one; its context still verifies, against no CA, so it could trust nothing."""
    return _with_ca() if url.lower().startswith("https:") else _without_ca()


@dataclass(frozen=True)
class ModelInfo:
    name: str
    detail: str = ""


class ChatClient:
    """Shared plumbing; subclasses speak one wire format."""

    kind = "base"

    def __init__(
        self,
        base_url: str,
        model: str,
        *,
        timeout_s: float = 120.0,
        connect_timeout_s: float = 5.0,
        api_key: str | None = None,
        slots: SlotRouter | None = None,
    ):
        self.base_url = base_url.rstrip("/")
        self.model = model
        self.timeout_s = timeout_s
        self.connect_timeout_s = connect_timeout_s
        self.api_key = api_key
        self.slots = slots

    @property
    def label(self) -> str:
        return f"{self.kind}:{self.model}@{self.base_url}"

    def _timeout(self) -> httpx.Timeout:
        # read timeout: the longest silence allowed between two chunks
        return httpx.Timeout(self.timeout_s, connect=self.connect_timeout_s)

    def _headers(self) -> dict[str, str]:
        return {"Authorization": f"Bearer {self.api_key}"} if self.api_key else {}

    async def chat(
        self,
        messages: Messages,
        *,
        max_tokens: int = 256,
        temperature: float = 0.0,
        schema: dict | None = None,
        on_token: OnToken | None = None,
        seed: int | None = 0,
        grammar: str | None = None,
        guard: bool = False,
        penalties: bool = False,
        deadline_s: float | None = None,
    ) -> Completion:
        """Stream a reply; `on_token` sees each piece of text. One retry if refused.

        `schema` constrains the reply to a JSON schema; `grammar` (llama.cpp servers only)
        to a GBNF grammar, and wins over `schema`. With `guard`, a reply that loops, or runs
        past `max_tokens` or `deadline_s` (a server may ignore the cap or never stop), is cut
        and ends with finish_reason "repetition", "length" or "deadline"."""
        slot = await self.slots.slot_for(messages) if self.slots else None
        opts = _Options(
            max_tokens, temperature, schema, seed, grammar, guard, penalties, deadline_s, slot
        )
        for attempt in (0, 1):
            try:
                completion = await self._chat_once(messages, opts, on_token)
                break
            except LLMUnavailable:
                if attempt == 1:
                    raise
                await asyncio.sleep(0.5)
        if self.slots and slot is not None:
            await self.slots.kept(slot, messages)
        return completion

    async def _chat_once(self, messages, opts: _Options, on_token) -> Completion:
        url, body = self._request(messages, opts)
        t0 = time.perf_counter()
        state = StreamState(t0)
        try:
            async with (
                httpx.AsyncClient(
                    timeout=self._timeout(), headers=self._headers(), verify=tls_for(url)
                ) as cl,
                cl.stream("POST", url, json=body) as resp,
            ):
                if resp.status_code >= 400:
                    detail = (await resp.aread()).decode("utf-8", "replace")[:200]
                    raise LLMHTTPError(
                        resp.status_code,
                        f"{self.label}: HTTP {resp.status_code}: {one_line(detail)}",
                    )
                async for piece in self._pieces(resp, state):
                    if piece:
                        state.add(piece)
                        if on_token:
                            on_token(piece)
                        if opts.guard and state.cut(opts.max_tokens, opts.deadline_s):
                            break
        except httpx.ConnectError as exc:
            raise _partial(
                LLMUnavailable(f"{self.label}: cannot connect ({one_line(str(exc))})"), state
            ) from None
        except httpx.TimeoutException:
            raise _partial(
                LLMTimeout(f"{self.label}: no answer within {self.timeout_s:g} s"), state
            ) from None
        except httpx.HTTPError as exc:
            raise _partial(
                LLMProtocolError(f"{self.label}: {type(exc).__name__}: {one_line(str(exc))}"),
                state,
            ) from None
        except LLMError as exc:
            raise _partial(exc, state) from None
        if not state.done:
            raise _partial(
                LLMProtocolError(f"{self.label}: the stream ended before the reply was complete"),
                state,
            )
        return state.completion()

    async def list_models(self) -> list[ModelInfo]:
        raise NotImplementedError

    async def _get_json(self, path: str) -> Any:
        try:
            async with httpx.AsyncClient(
                timeout=httpx.Timeout(5.0), headers=self._headers(), verify=tls_for(self.base_url)
            ) as cl:
                resp = await cl.get(f"{self.base_url}{path}")
        except httpx.HTTPError as exc:
            detail = one_line(str(exc)) or type(exc).__name__
            raise LLMUnavailable(f"{self.label}: {detail}") from None
        if resp.status_code >= 400:
            raise LLMHTTPError(resp.status_code, f"{self.label}: HTTP {resp.status_code}")
        try:
            return resp.json()
        except ValueError:
            raise LLMProtocolError(f"{self.label}: {path} did not return JSON") from None

    def _request(self, messages: Messages, opts: _Options) -> tuple[str, dict]:
        raise NotImplementedError

    def _pieces(self, resp: httpx.Response, state: StreamState) -> AsyncIterator[str]:
        raise NotImplementedError

    def _chunk(self, text: str) -> dict[str, Any]:
        """One streamed JSON object; an error object from the server becomes an exception."""
        try:
            chunk = json.loads(text)
        except json.JSONDecodeError:
            raise LLMProtocolError(
                f"{self.label}: malformed JSON in stream: {text[:80]!r}"
            ) from None
        if not isinstance(chunk, dict):
            raise LLMProtocolError(f"{self.label}: unexpected stream item: {text[:80]!r}")
        if "error" in chunk:
            raise LLMHTTPError(500, f"{self.label}: {one_line(str(chunk['error']))}")
        return chunk


def _partial(exc: LLMError, state: StreamState) -> LLMError:
    """The exception, carrying what the reply said before it failed (kept with the turn)."""
    exc.partial = "".join(state.parts)
    return exc


class OpenAIClient(ChatClient):
    """llama.cpp's server, vLLM, Docker Model Runner, LM Studio, Ollama's /v1."""

    kind = "openai"

    def _request(self, messages, opts):
        body: dict[str, Any] = {
            "model": self.model,
            "messages": messages,
            "stream": True,
            "stream_options": {"include_usage": True},
            "max_tokens": opts.max_tokens,
            "temperature": opts.temperature,
        }
        if opts.seed is not None:
            body["seed"] = opts.seed
        if opts.slot is not None:
            body["id_slot"] = opts.slot  # llama.cpp's server extension
        if opts.penalties:  # llama.cpp's server extensions, like `grammar`
            body.update(repeat_penalty=1.15, repeat_last_n=64, dry_multiplier=0.8)
        if opts.grammar is not None:
            body["grammar"] = opts.grammar  # llama.cpp's server extension
        elif opts.schema is not None:
            body["response_format"] = {
                "type": "json_schema",
                "json_schema": {"name": "reply", "strict": True, "schema": opts.schema},
            }
        return f"{self.base_url}/chat/completions", body

    async def _pieces(self, resp, state):
        async for line in resp.aiter_lines():
            line = line.strip()
            if not line or line.startswith(":"):
                continue
            if not line.startswith("data:"):
                raise LLMProtocolError(f"{self.label}: unexpected line in stream: {line[:80]!r}")
            data = line[5:].strip()
            if data == "[DONE]":
                state.done = True
                return
            chunk = self._chunk(data)
            usage = chunk.get("usage")
            if usage:
                state.prompt_tokens = usage.get("prompt_tokens")
                state.completion_tokens = usage.get("completion_tokens")
                details = usage.get("prompt_tokens_details") or {}
                state.cached_tokens = details.get("cached_tokens")
            timings = chunk.get("timings")
            if timings and timings.get("predicted_ms"):
                state.gen_seconds = timings["predicted_ms"] / 1000.0
                state.completion_tokens = timings.get("predicted_n", state.completion_tokens)
            for choice in chunk.get("choices") or []:
                delta = choice.get("delta") or {}
                if choice.get("finish_reason"):
                    state.finish_reason = choice["finish_reason"]
                content = delta.get("content")
                if content:
                    yield content
        # some servers end without [DONE] after a finish_reason
        state.done = state.finish_reason is not None

    async def list_models(self) -> list[ModelInfo]:
        data = await self._get_json("/models")
        return [ModelInfo(m.get("id", "?")) for m in data.get("data", [])]


def _ollama_message(message: dict[str, Any]) -> dict[str, Any]:
    """OpenAI's content parts in Ollama's native form: the text, and its images as a list of
    base64 strings (no data: prefix)."""
    parts = message.get("content")
    if not isinstance(parts, list):
        return message
    text = "".join(p.get("text", "") for p in parts if p.get("type") == "text")
    urls = [p["image_url"]["url"] for p in parts if p.get("type") == "image_url"]
    images = [u.partition(";base64,")[2] or u for u in urls]
    return {**message, "content": text, **({"images": images} if images else {})}


class OllamaClient(ChatClient):
    """Ollama's native /api/chat: its eval counts and durations give exact tokens/s."""

    kind = "ollama"

    def _request(self, messages, opts):
        options: dict[str, Any] = {"num_predict": opts.max_tokens, "temperature": opts.temperature}
        if opts.seed is not None:
            options["seed"] = opts.seed
        if opts.penalties:
            options["repeat_penalty"] = 1.15
        body: dict[str, Any] = {
            "model": self.model,
            "messages": [_ollama_message(m) for m in messages],
            "stream": True,
            "options": options,
        }
        if opts.schema is not None:
            body["format"] = opts.schema
        return f"{self.base_url}/api/chat", body

    async def _pieces(self, resp, state):
        async for line in resp.aiter_lines():
            if not line.strip():
                continue
            chunk = self._chunk(line)
            content = (chunk.get("message") or {}).get("content")
            if content:
                yield content
            if chunk.get("done"):
                state.done = True
                state.finish_reason = chunk.get("done_reason", "stop")
                cached = chunk.get("prompt_eval_cached_count") or 0
                if "prompt_eval_count" in chunk:
                    state.prompt_tokens = max(chunk["prompt_eval_count"] - cached, 0)
                state.cached_tokens = cached
                state.completion_tokens = chunk.get("eval_count")
                if chunk.get("eval_duration"):
                    state.gen_seconds = chunk["eval_duration"] / 1e9
                return

    async def list_models(self) -> list[ModelInfo]:
        data = await self._get_json("/api/tags")
        return [
            ModelInfo(m.get("name", "?"), m.get("details", {}).get("parameter_size", ""))
            for m in data.get("models", [])
        ]

"""One string picks the model: rules, embedded, gguf:PATH, ollama:NAME[@URL], openai:NAME@URL,
dmr:NAME (Docker Model Runner's default local endpoint)."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import urlsplit

from astiop.agent.models.embedded import EmbeddedServer, smollm2_path

if TYPE_CHECKING:
    from astiop.agent.models.llm import ChatClient

OLLAMA_URL = "http://localhost:11434"
DMR_URL = "http://localhost:12434/engines/v1"
SPEC_HELP = "rules, embedded, gguf:/path/model.gguf, ollama:NAME[@URL], openai:NAME@URL, dmr:NAME"
SEEING_KINDS = ("ollama", "openai", "dmr")  # servers that may take images; the embedded one never


class SpecError(ValueError):
    pass


@dataclass(frozen=True)
class ModelSpec:
    raw: str
    kind: str  # rules | embedded | gguf | ollama | openai | dmr
    name: str = ""
    url: str = ""
    path: Path | None = None


def parse_spec(text: str) -> ModelSpec:
    raw = (text or "").strip()
    if raw in ("rules", "embedded"):
        return ModelSpec(raw, raw)
    kind, sep, rest = raw.partition(":")
    if not sep or not rest:
        raise SpecError(f"'{raw}' is not a model spec (use {SPEC_HELP})")
    if kind == "gguf":
        path = Path(rest).expanduser()
        if not path.is_file():
            raise SpecError(f"GGUF file {path} does not exist")
        try:
            with path.open("rb") as fh:
                magic = fh.read(4)
        except OSError as exc:
            raise SpecError(f"cannot read {path}: {exc.strerror or exc}") from None
        if magic != b"GGUF":
            raise SpecError(f"{path} is not a GGUF file (it does not start with 'GGUF')")
        return ModelSpec(raw, "gguf", path.stem, path=path)
    name, at, url = rest.rpartition("@") if "@" in rest else (rest, "", "")
    if url:
        _check_url(raw, url)
    if kind == "ollama":
        return ModelSpec(raw, "ollama", name, url or OLLAMA_URL)
    if kind == "dmr":
        return ModelSpec(raw, "dmr", name, url or DMR_URL)
    if kind == "openai":
        if not at or not url:
            raise SpecError(
                f"'{raw}': an openai spec needs a URL, like "
                "openai:ai/gemma3@http://localhost:12434/engines/v1"
            )
        return ModelSpec(raw, "openai", name, url)
    raise SpecError(f"unknown model kind '{kind}' in '{raw}' (use {SPEC_HELP})")


def _check_url(raw: str, url: str) -> None:
    """An http(s) URL with a host and a port in range, or a one-line reason."""
    try:
        parts = urlsplit(url)
        port = parts.port  # raises on a port that is not a number in 0..65535
    except ValueError as exc:
        raise SpecError(f"'{raw}': the URL {url!r} is malformed ({exc})") from None
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise SpecError(f"'{raw}': the URL must be http(s)://HOST[:PORT][/PATH], not {url!r}")
    if port == 0:
        raise SpecError(f"'{raw}': port 0 is not a server's port")


class LLMEndpoint:
    """A spec made usable: its client, and for embedded models the server it starts."""

    def __init__(
        self,
        spec: ModelSpec,
        *,
        threads: int | None = None,
        n_ctx: int = 4096,
        timeout_s: float = 120.0,
        vision: bool = False,
    ):
        self.spec = spec
        self.vision = vision  # the operator says this model takes images (`llm.vision`)
        self.threads = threads
        self.n_ctx = n_ctx
        self.timeout_s = timeout_s
        self.server: EmbeddedServer | None = None
        self._client: ChatClient | None = None
        self._lock = threading.Lock()  # the console's warm-up and its first question at once
        self.warming = False  # set while `astiop.agent.warm` evaluates this robot's prompts

    @property
    def is_rules(self) -> bool:
        return self.spec.kind == "rules"

    @property
    def sees(self) -> bool:
        """Whether a question about the robot's view is sent the camera's frame: a model marked
        as taking images, on a server that can be sent them (not SmolLM2, not the rules)."""
        return self.vision and self.spec.kind in SEEING_KINDS

    @property
    def local(self) -> bool:
        return self.spec.kind in ("embedded", "gguf")

    def launch(self) -> None:
        """Starts loading an embedded model now, without waiting for it (a no-op for others):
        the first `client()` finds it loaded or loading."""
        if self.local and self.server is None:
            path = smollm2_path() if self.spec.kind == "embedded" else self.spec.path
            self.server = EmbeddedServer(path, self.threads, self.n_ctx).launch()

    def client(self) -> ChatClient:
        """The chat client; starts the embedded server on first use (about half a second)."""
        with self._lock:
            return self._client_locked()

    def _client_locked(self) -> ChatClient:
        if self._client is None:
            from astiop.agent.models.llm import OllamaClient, OpenAIClient  # after `launch`: httpx

            spec = self.spec
            if self.local:
                self.launch()
                self._client = self.server.start().client(self.timeout_s)
            elif spec.kind == "ollama":
                self._client = OllamaClient(spec.url, spec.name, timeout_s=self.timeout_s)
            elif spec.kind in ("openai", "dmr"):
                self._client = OpenAIClient(spec.url, spec.name, timeout_s=self.timeout_s)
            else:
                raise SpecError("the rules planner has no chat client")
        return self._client

    def completions(self) -> tuple[str, str]:
        """The OpenAI-compatible `chat/completions` URL and the model name, as a plain HTTP
        client (the paper's benchmark scripts) reaches this model."""
        spec = self.spec
        if spec.kind == "rules":
            raise SpecError("the rules planner is not a model server")
        client = self.client()  # starts the embedded server
        if spec.kind in ("embedded", "gguf"):
            return f"{self.server.base_url}/chat/completions", self.server.model_name
        base = spec.url.rstrip("/") + ("/v1" if spec.kind == "ollama" else "")
        return f"{base}/chat/completions", getattr(client, "model", spec.name)

    def close(self, wait_s: float = 5.0) -> None:
        if self.server is not None:
            self.server.stop(wait_s)
            self.server = None
        self._client = None


def open_endpoint(
    text: str,
    *,
    threads: int | None = None,
    n_ctx: int = 4096,
    timeout_s: float = 120.0,
    vision: bool = False,
) -> LLMEndpoint:
    spec = parse_spec(text)
    return LLMEndpoint(spec, threads=threads, n_ctx=n_ctx, timeout_s=timeout_s, vision=vision)

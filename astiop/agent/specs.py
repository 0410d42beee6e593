"""One string picks the model: rules, embedded, gguf:PATH, ollama:NAME[@URL], openai:NAME@URL,
dmr:NAME (Docker Model Runner's default local endpoint)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from astiop.agent.embedded import EmbeddedServer, smollm2_path
from astiop.agent.llm import ChatClient, OllamaClient, OpenAIClient

OLLAMA_URL = "http://localhost:11434"
DMR_URL = "http://localhost:12434/engines/v1"
SPEC_HELP = "rules, embedded, gguf:/path/model.gguf, ollama:NAME[@URL], openai:NAME@URL, dmr:NAME"


class SpecError(ValueError):
    pass


@dataclass(frozen=True)
class ModelSpec:
    raw: str
    kind: str  # rules | embedded | gguf | ollama | openai | dmr
    name: str = ""
    url: str = ""
    path: Path | None = None

    @property
    def label(self) -> str:
        return self.raw


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
        return ModelSpec(raw, "gguf", path.stem, path=path)
    name, at, url = rest.rpartition("@") if "@" in rest else (rest, "", "")
    if kind == "ollama":
        return ModelSpec(raw, "ollama", name, url or OLLAMA_URL)
    if kind == "dmr":
        return ModelSpec(raw, "dmr", name, url or DMR_URL)
    if kind == "openai":
        if not at or not url.startswith(("http://", "https://")):
            raise SpecError(
                f"'{raw}': an openai spec needs a URL, like "
                "openai:ai/gemma3@http://localhost:12434/engines/v1"
            )
        return ModelSpec(raw, "openai", name, url)
    raise SpecError(f"unknown model kind '{kind}' in '{raw}' (use {SPEC_HELP})")


class LLMEndpoint:
    """A spec made usable: its client, and for embedded models the server it starts."""

    def __init__(
        self,
        spec: ModelSpec,
        *,
        threads: int | None = None,
        n_ctx: int = 4096,
        timeout_s: float = 120.0,
    ):
        self.spec = spec
        self.threads = threads
        self.n_ctx = n_ctx
        self.timeout_s = timeout_s
        self.server: EmbeddedServer | None = None
        self._client: ChatClient | None = None

    @property
    def is_rules(self) -> bool:
        return self.spec.kind == "rules"

    @property
    def local(self) -> bool:
        return self.spec.kind in ("embedded", "gguf")

    def client(self) -> ChatClient:
        """The chat client; starts the embedded server on first use (about a second)."""
        if self._client is None:
            spec = self.spec
            if spec.kind in ("embedded", "gguf"):
                path = smollm2_path() if spec.kind == "embedded" else spec.path
                self.server = EmbeddedServer(path, self.threads, self.n_ctx).start()
                self._client = OpenAIClient(
                    self.server.base_url, self.server.model_name, timeout_s=self.timeout_s
                )
            elif spec.kind == "ollama":
                self._client = OllamaClient(spec.url, spec.name, timeout_s=self.timeout_s)
            elif spec.kind in ("openai", "dmr"):
                self._client = OpenAIClient(spec.url, spec.name, timeout_s=self.timeout_s)
            else:
                raise SpecError("the rules planner has no chat client")
        return self._client

    def close(self) -> None:
        if self.server is not None:
            self.server.stop()
            self.server = None
        self._client = None


def open_endpoint(
    text: str, *, threads: int | None = None, n_ctx: int = 4096, timeout_s: float = 120.0
) -> LLMEndpoint:
    return LLMEndpoint(parse_spec(text), threads=threads, n_ctx=n_ctx, timeout_s=timeout_s)

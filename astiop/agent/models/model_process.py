"""The embedded model's own process: llama.cpp's server (xllamacpp), run by
`embedded.EmbeddedServer` as `python -I model_process.py`.

In a process of its own, loading the model (~0.4 s, with the GIL held throughout) overlaps the
parent's imports and the robot's start, and never freezes the console. It imports xllamacpp,
then reads its settings as one JSON line on stdin (so a process started ahead, `model_spawn`,
has it loaded by then) and answers one JSON line on stdout: what it runs (the prompt cache's
build is named for it) or why it cannot start. It serves until its stdin closes, that is until
the parent stops it or ends, however it ends. Only the standard library and xllamacpp here.
"""

from __future__ import annotations

import functools
import importlib.metadata
import json
import os
import sys


def serve(config: dict):
    """The server, and what it runs."""
    import xllamacpp

    params = xllamacpp.CommonParams()
    params.model.path = config["model"]
    params.port = config["port"]
    params.cpuparams.n_threads = config["threads"]
    params.cpuparams_batch.n_threads = config["threads"]
    params.use_jinja = True
    params.verbosity = -1
    params.warmup = False  # an empty decode at start: 30-40 ms the first call need not wait
    params.fit_params = config["fit_params"]
    # One slot per kind of call, each with a KV cache of its own and the whole context; flash
    # attention off. Both so that a reply never depends on what was cached: llama.cpp's CPU
    # flash attention rounds by how a prompt was split, and a shared cache by where its cells
    # landed. A reused prefix answered unlike a cold prefill in 10 of 32 held-out
    # interpretations with one slot and flash attention, 21 of 32 with a shared cache and
    # without; with both settings, 0 of 32 plans and answers.
    params.n_parallel = config["slots"]
    params.kv_unified = False
    params.n_ctx = config["n_ctx"] * config["slots"]
    params.cache_idle_slots = False  # nothing to gain: each kind keeps its own slot
    params.flash_attn_type = 0  # LLAMA_FLASH_ATTN_TYPE_DISABLED
    if config.get("slot_save_path"):
        params.slot_save_path = config["slot_save_path"]
        params.endpoint_slots = True
    server = xllamacpp.Server(params)
    runs = {
        "xllamacpp": _version(),
        "build": repr(getattr(xllamacpp, "BUILD_INFO", "")),
        "n_ctx": params.n_ctx,
        "slots": params.n_parallel,
        "kv_unified": params.kv_unified,
        "batch": [params.n_batch, params.n_ubatch],
        "cache_types": [int(params.cache_type_k), int(params.cache_type_v)],
        "flash_attn": int(params.flash_attn_type),
    }
    return server, runs


@functools.cache
def _version() -> str:
    try:
        return importlib.metadata.version("xllamacpp")
    except importlib.metadata.PackageNotFoundError:
        return ""


def _reply(data: dict) -> None:
    sys.stdout.write(json.dumps(data) + "\n")
    sys.stdout.flush()


def main() -> None:
    try:  # before the settings: a process started ahead (`model_spawn`) loads it meanwhile
        import xllamacpp  # noqa: F401

        _version()
    except Exception:
        pass  # `serve` says why
    line = sys.stdin.readline(64 * 1024)
    if not line:
        return  # started ahead, and not wanted
    try:
        config = json.loads(line)
        server, runs = serve(config)
    except Exception as exc:  # the parent says it in one line
        _reply({"error": f"{type(exc).__name__}: {exc}"})
        return
    _reply({"ready": runs})
    while sys.stdin.buffer.read(4096):
        pass
    os._exit(0)  # no teardown (50 ms): the OS frees the model at once; `server` lives till here


if __name__ == "__main__":
    main()

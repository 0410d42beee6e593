"""Scripted LLM servers on 127.0.0.1 for tests: OpenAI-compatible SSE and Ollama NDJSON.

Real HTTP, real sockets; the reply text and the failure mode are chosen by the test.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from collections.abc import Callable
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

Reply = str | Callable[[list[dict]], str]


class _Server(ThreadingHTTPServer):
    errors: list[BaseException]

    def handle_error(self, request, client_address) -> None:
        """Kept, never printed: a handler outliving its test (a client that hung up, a stream
        canceled) would print into whatever stderr another test of this process captures."""
        self.errors.append(sys.exc_info()[1])


class ScriptedLLM:
    def __init__(self, flavour: str = "openai"):
        self.flavour = flavour
        self.replies: list[Reply] = []
        self.default: Reply = "ok"
        self.mode = "ok"  # ok | slow | garbage | http500 | truncated | endless
        self.endless: Callable[[int], str] = lambda i: "again "  # piece i in endless mode
        self.delay_s = 0.0
        self.requests: list[dict] = []
        self.timings = False  # send llama.cpp `timings` in the last chunk
        handler = self._handler()
        self.httpd = _Server(("127.0.0.1", 0), handler)
        self.httpd.errors = []
        self.port = self.httpd.server_address[1]
        self._thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self._thread.start()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}" + ("/v1" if self.flavour == "openai" else "")

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()

    def next_text(self, messages: list[dict]) -> str:
        reply = self.replies.pop(0) if self.replies else self.default
        return reply(messages) if callable(reply) else reply

    def _handler(self):
        server = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.0"

            def log_message(self, *args):
                pass

            def do_GET(self):
                if self.path.endswith("/models"):
                    body = {"data": [{"id": "scripted-model"}]}
                elif self.path.endswith("/api/tags"):
                    body = {
                        "models": [{"name": "scripted:1b", "details": {"parameter_size": "1B"}}]
                    }
                else:
                    self.send_error(404)
                    return
                self._json(200, body)

            def _json(self, code, body):
                data = json.dumps(body).encode()
                self.send_response(code)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def do_POST(self):
                length = int(self.headers.get("Content-Length", 0))
                body = json.loads(self.rfile.read(length) or b"{}")
                server.requests.append(body)
                if server.mode == "slow":
                    time.sleep(server.delay_s)
                if server.mode == "http500":
                    self._json(500, {"error": {"message": "model crashed\nbadly"}})
                    return
                if server.mode == "http503":
                    self._json(503, {"error": {"message": "loading model"}})
                    return
                if body.get("stream") is False:  # one JSON reply, as a plain client asks
                    text = server.next_text(body.get("messages", []))
                    words = len(text.split())
                    self._json(200, {
                        "choices": [{"index": 0, "message": {"role": "assistant", "content": text},
                                     "finish_reason": "stop"}],
                        "usage": {"prompt_tokens": 42, "completion_tokens": words,
                                  "total_tokens": 42 + words},
                    })  # fmt: skip
                    return
                self.send_response(200)
                self.send_header("Content-Type", "text/event-stream")
                self.end_headers()
                if server.mode == "endless":  # a server that never stops: until we hang up
                    self._endless()
                    return
                text = server.next_text(body.get("messages", []))
                pieces = [text[i : i + 3] for i in range(0, len(text), 3)] or [""]
                if server.flavour == "openai":
                    self._openai(pieces, text)
                else:
                    self._ollama(pieces)

            def _endless(self):
                try:
                    for i in range(10**6):
                        chunk = {"choices": [{"index": 0, "delta": {"content": server.endless(i)}}]}
                        self._send(f"data: {json.dumps(chunk)}\n\n")
                        time.sleep(server.delay_s)
                except OSError:
                    pass  # the client hung up

            def _send(self, line: str):
                self.wfile.write(line.encode())
                self.wfile.flush()

            def _openai(self, pieces, text):
                self._send('data: {"choices":[{"index":0,"delta":{"role":"assistant"}}]}\n\n')
                if server.mode == "garbage":
                    self._send("data: {this is not json\n\n")
                    return
                for i, p in enumerate(pieces):
                    if server.mode == "truncated" and i == len(pieces) // 2:
                        self._send('data: {"choices":[{"index":0,"delta":{"content":"x')
                        return
                    chunk = {"choices": [{"index": 0, "delta": {"content": p}}], "usage": None}
                    self._send(f"data: {json.dumps(chunk)}\n\n")
                final = {"choices": [{"index": 0, "delta": {}, "finish_reason": "stop"}]}
                self._send(f"data: {json.dumps(final)}\n\n")
                usage = {
                    "choices": [],
                    "usage": {
                        "prompt_tokens": 42,
                        "completion_tokens": len(pieces),
                        "prompt_tokens_details": {"cached_tokens": 2},
                    },
                }
                if server.timings:
                    usage["timings"] = {"predicted_n": len(pieces), "predicted_ms": 500.0}
                self._send(f"data: {json.dumps(usage)}\n\n")
                self._send("data: [DONE]\n\n")

            def _ollama(self, pieces):
                if server.mode == "garbage":
                    self._send("{nope\n")
                    return
                for i, p in enumerate(pieces):
                    if server.mode == "truncated" and i == len(pieces) // 2:
                        self._send('{"message": {"content": "x')
                        return
                    self._send(
                        json.dumps({"message": {"role": "assistant", "content": p}, "done": False})
                        + "\n"
                    )
                self._send(
                    json.dumps(
                        {
                            "message": {"role": "assistant", "content": ""},
                            "done": True,
                            "done_reason": "stop",
                            "prompt_eval_count": 50,
                            "prompt_eval_cached_count": 20,
                            "eval_count": len(pieces),
                            "eval_duration": 250_000_000,
                            "total_duration": 400_000_000,
                        }
                    )
                    + "\n"
                )

        return Handler

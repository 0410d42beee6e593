"""A streamed reply as it arrives, and the guard that cuts one that loops or runs on."""

from __future__ import annotations

import re
import time
from dataclasses import dataclass


@dataclass
class Completion:
    text: str
    ttft_s: float | None
    total_s: float
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    tokens_per_s: float | None = None
    finish_reason: str | None = None
    cached_tokens: int | None = None


def repeating(text: str) -> bool:
    """The text ends in a loop: its last n words three times over (one word: six times)."""
    words = re.findall(r"\S+", text[-800:])
    for n in range(1, 16):
        times = 6 if n == 1 else 3
        if len(words) < n * times:
            return False
        tail = words[-n:]
        if all(words[len(words) - (k + 1) * n : len(words) - k * n] == tail for k in range(times)):
            return True
    return False


class StreamState:
    """One streamed reply as it arrives: its pieces, time to first token, usage."""

    def __init__(self, t0: float):
        self.t0 = t0
        self.parts: list[str] = []
        self.ttft: float | None = None
        self.done = False
        self.finish_reason: str | None = None
        self.prompt_tokens: int | None = None
        self.completion_tokens: int | None = None
        self.cached_tokens: int | None = None
        self.gen_seconds: float | None = None

    def add(self, piece: str) -> None:
        if self.ttft is None and piece.strip():
            self.ttft = time.perf_counter() - self.t0
        self.parts.append(piece)

    def cut(self, max_tokens: int, deadline_s: float | None) -> bool:
        """Whether the reply must stop here; if so, it is marked done with the reason."""
        if len(self.parts) > max_tokens + 8:  # a streamed piece is about one token
            reason = "length"
        elif deadline_s is not None and time.perf_counter() - self.t0 > deadline_s:
            reason = "deadline"
        elif repeating("".join(self.parts[-200:])):
            reason = "repetition"
        else:
            return False
        self.done, self.finish_reason = True, reason
        return True

    def completion(self) -> Completion:
        total = time.perf_counter() - self.t0
        tps = None
        if self.completion_tokens and self.gen_seconds:
            tps = self.completion_tokens / self.gen_seconds
        elif self.completion_tokens and self.ttft is not None and total > self.ttft:
            tps = max(self.completion_tokens - 1, 1) / (total - self.ttft)
        return Completion(
            "".join(self.parts),
            self.ttft,
            total,
            self.prompt_tokens,
            self.completion_tokens,
            tps,
            self.finish_reason,
            self.cached_tokens,
        )

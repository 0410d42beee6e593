"""Scores as the paper defines them: stage 1 (Eq. 1-2) and stage 2 (Eq. 9-10).

Per-case stage-1 quality (our stated formula, 0-100):
  Q = 0.30·L + 0.25·K + 0.20·T + 0.25·C
  L length: 100 between 80 and 600 words, linear below 80, easing to 50 above 600
  K code: where code is expected, 100 if every block checks (Python parses, YAML and XML
    load), 50 if some block fails, 0 with no block; where none is expected, 100 unless a
    block fails (50)
  T structure: 25 each for several paragraphs, a list, headings or bold terms, code or
    inline code
  C coverage: the share of expected topics mentioned (any accepted spelling)
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import yaml

FENCE = re.compile(r"```([\w+-]*)\s*\n(.*?)```", re.S)


@dataclass(frozen=True)
class CodeCheck:
    blocks: int
    valid: int


def check_code(text: str) -> CodeCheck:
    blocks = FENCE.findall(text)
    valid = 0
    for lang, body in blocks:
        lang = lang.lower()
        try:
            if lang in ("python", "py", "python3"):
                # compile, not ast.parse: CPython 3.11.7's ast.parse leaves its recursion
                # counter unbalanced after a syntax error, and the next parse then fails
                compile(body, "<answer>", "exec", dont_inherit=True)
            elif lang in ("yaml", "yml"):
                yaml.safe_load(body)
            elif lang in ("xml", "launch") or lang == "" and body.lstrip().startswith("<"):
                ET.fromstring(body)
            # other languages (bash, cpp, cmake) are counted, not checked
            valid += 1
        except (SyntaxError, ValueError, yaml.YAMLError, ET.ParseError):
            pass
    return CodeCheck(len(blocks), valid)


def coverage(text: str, topics) -> float:
    lowered = text.lower()
    hit = sum(1 for spellings in topics if any(s.lower() in lowered for s in spellings))
    return 100.0 * hit / len(topics) if topics else 0.0


def length_score(words: int) -> float:
    if words < 80:
        return 100.0 * words / 80
    if words <= 600:
        return 100.0
    return max(50.0, 100.0 - (words - 600) / 10)


def structure_score(text: str) -> float:
    points = 0
    points += len([p for p in text.split("\n\n") if p.strip()]) >= 2
    points += bool(re.search(r"^\s*([-*]|\d+\.)\s+\S", text, re.M))
    points += bool(re.search(r"^#{1,4}\s|\*\*[^*]+\*\*", text, re.M))
    points += bool(FENCE.search(text) or re.search(r"`[^`]+`", text))
    return 25.0 * points


def code_score(text: str, expected: str) -> float:
    check = check_code(text)
    if expected == "none":
        return 100.0 if check.valid == check.blocks else 50.0
    if check.blocks == 0:
        return 0.0
    return 100.0 if check.valid == check.blocks else 50.0


def quality(text: str, topics, code_expected: str) -> float:
    words = len(text.split())
    return (
        0.30 * length_score(words)
        + 0.25 * code_score(text, code_expected)
        + 0.20 * structure_score(text)
        + 0.25 * coverage(text, topics)
    )


# -- composites --------------------------------------------------------------------------
def speed_scores(tokens_per_s: dict[str, float]) -> dict[str, float]:
    """Eq. 2: each model's mean tokens/s against the fastest in the run, capped at 100."""
    fastest = max(tokens_per_s.values(), default=0.0)
    return {
        k: min(100.0 * v / fastest, 100.0) if fastest > 0 else 0.0 for k, v in tokens_per_s.items()
    }


def paper_speed(mean_tokens_per_s: float, fastest_case: float) -> float:
    """Eq. 2 as the paper computed Table 8: a model's mean tokens/s (over every test) against
    the fastest single test of the run, capped at 100. (Against the fastest model's mean, the
    fastest model would score 100; Table 8 gives SmolLM2, the fastest, 86.04.)"""
    if fastest_case <= 0:
        return 0.0
    return min(100.0 * mean_tokens_per_s / fastest_case, 100.0)


def stage1_composite(q: float, c: float, sp: float, r: float) -> float:
    """Eq. 1."""
    return 0.35 * q + 0.3 * c + 0.2 * sp + 0.15 * r


def stage2_speed(mean_total_s: float, max_total_s: float) -> float:
    """Eq. 10, Sp: 100 minus the mean task time as a share of the slowest task in the run."""
    if max_total_s <= 0:
        return 0.0
    return max(0.0, 100.0 - 100.0 * mean_total_s / max_total_s)


def stage2_composite(c: float, i: float, bv: float, sp: float) -> float:
    """Eq. 9."""
    return 0.25 * c + 0.25 * i + 0.3 * bv + 0.2 * sp

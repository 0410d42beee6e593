"""A per-turn GBNF grammar for the interpretation (llama.cpp servers only).

A small model writes its answer in its own words, but only words it may use this turn: plain
connecting words, the robot's vocabulary, the words of the request and of the results, and the
results' numbers each with the unit the results give it (so a voltage cannot be written as a
speed). A claim word (arrived, charging, moving, ...) is allowed only when this turn's facts
support it. The model then cannot invent telemetry, places or events; grounding still checks
every sentence afterwards.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable
from functools import cache

from astiop.agent.grounding import OBSTACLE_KINDS, STATE_CLAIMS
from astiop.agent.stated_numbers import written_figures
from astiop.resources import prompts_path

_WORD = re.compile(r"[A-Za-z][A-Za-z_'-]*")
ARRIVAL_WORDS = {"arrived", "arrives", "reached", "reaches", "navigated", "completed", "finished"}
COMMANDED_LEADS = ["Commanded", "Sent"]
MAX_FACTS = 48  # a long listing (every location) keeps its first numbers only
MAX_ITEMS = 28  # words and figures in one sentence


@cache
def lexicon() -> tuple[str, ...]:
    """The words any answer may use: prompts/answer_words.txt, one or more per line."""
    text = prompts_path("answer_words.txt").read_text(encoding="utf-8")
    lines = (line.split("#", 1)[0] for line in text.splitlines())
    return tuple(w for line in lines for w in line.split())


@cache
def _lexicon_kinds() -> frozenset[str]:
    """The obstacle kinds the lexicon names (allowed only when the robot reported one)."""
    return frozenset(m.group().lower() for m in OBSTACLE_KINDS.finditer(" ".join(lexicon())))


def _claim_words(supported: set[str]) -> tuple[set[str], set[str]]:
    """(claim words the facts support, claim words they do not); a claim of several words is
    left to grounding (its words are common ones)."""
    allowed, banned = set(), set()
    for claim, support in STATE_CLAIMS.items():
        if " " not in claim:
            (allowed if support & supported else banned).add(claim)
    (allowed if "arrived" in supported else banned).update(ARRIVAL_WORDS)
    return allowed, banned


def quantities(results: str) -> list[str]:
    """The results' numbers as the answer may write them: with their unit, each once."""
    found: dict[str, None] = {}
    for number, unit in written_figures(results):  # as grounding reads them
        found[f"{number} {unit}".strip()] = None
        if unit and number.endswith(".0"):
            found[f"{number[:-2]} {unit}"] = None
    return list(found)[:MAX_FACTS]


def answer_grammar(
    request: str,
    results: str,
    supported: Iterable[str] = (),
    kinds: Iterable[str] = (),
    commanded_only: bool = False,
) -> str:
    """One or two sentences of allowed words and figures; `supported` are the fact words of
    this turn (grounding.Facts.words), `kinds` the obstacle kinds reported. When all that ran
    was commanded (a Twist published), the answer opens by saying so: nothing was measured."""
    supported = set(supported)
    allowed_claims, banned = _claim_words(supported)
    kinds = {k.lower() for k in kinds}
    banned |= _lexicon_kinds() - kinds  # an obstacle kind the robot did not report
    words = dict.fromkeys(w.lower() for w in lexicon())
    said = [line for line in results.splitlines() if not line.startswith("ros2 ")]
    words.update(dict.fromkeys(w.lower() for w in _WORD.findall(" ".join([request, *said]))))
    words.update(dict.fromkeys(allowed_claims | kinds | {k + "s" for k in kinds}))
    vocab = [w for w in words if w not in banned or w in allowed_claims or w in kinds]
    figures = sorted(quantities(results), key=len, reverse=True)  # 27.12 V before 27 V
    first = COMMANDED_LEADS if commanded_only else sorted({w.capitalize() for w in vocab} | {"I"})
    rules = [
        'root ::= sentence (" " sentence)?',
        f'sentence ::= first (sep item){{0,{MAX_ITEMS}}} "."',
        'sep ::= " " | ", " | "; " | ": " | " - "',
        "first ::= " + _alternatives(first),
        "item ::= word" + (" | figure" if figures else ""),
        "word ::= " + _alternatives(sorted(vocab)),
    ]
    if figures:
        rules.append("figure ::= " + _alternatives(figures))
    return "\n".join(rules) + "\n"


def _alternatives(items: Iterable[str]) -> str:
    """The strings as one GBNF expression, factored as a trie: llama.cpp follows one stack per
    open alternative, so shared prefixes keep sampling fast."""
    return _trie(sorted(set(items)))


def _trie(words: list[str]) -> str:
    ends = "" in words
    rest = [w for w in words if w]
    groups: dict[str, list[str]] = {}
    for w in rest:
        groups.setdefault(w[0], []).append(w[1:])
    parts = []
    for first, tails in groups.items():
        prefix = first
        while len(tails) > 1 and "" not in tails and len({t[0] for t in tails}) == 1:
            prefix += tails[0][0]
            tails = [t[1:] for t in tails]
        if tails == [""]:
            parts.append(json.dumps(prefix))
        elif len(tails) == 1:
            parts.append(json.dumps(prefix + tails[0]))
        else:
            parts.append(f"{json.dumps(prefix)} ({_trie(tails)})")
    body = " | ".join(parts)
    return f"({body})?" if ends else body

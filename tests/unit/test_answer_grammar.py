"""The interpretation grammar: the words and figures an answer may use this turn, held by the
real llama.cpp server (the embedded model), whatever the model is asked to write."""

import re

from astiop.agent.answer_grammar import _alternatives, answer_grammar, quantities

BATTERY = "ros2 topic echo --once /battery_status sensor_msgs/msg/BatteryState\n  battery 85.0 %, 27.12 V, 4.40 A, charging"
OBSTACLE = "ros2 topic echo --once /obstacles astiop_msgs/msg/ObstacleArray\n  1 obstacle(s) detected: pallet at 2.4 m, bearing 2 deg"


def spelled(grammar: str, rule: str = "word") -> set[str]:
    """Every string one of the grammar's rules spells (the trie expanded)."""
    line = next(line for line in grammar.splitlines() if line.startswith(f"{rule} ::= "))
    return set(_expand(line.removeprefix(f"{rule} ::= ")))


def _expand(expr: str) -> list[str]:
    # a small GBNF subset: "lit", (a | b), x? and sequences, as _alternatives writes them
    out, depth, start, parts = [], 0, 0, []
    for i, ch in enumerate(expr + " |"):
        depth += (ch == "(") - (ch == ")")
        if ch == "|" and depth == 0:
            parts.append(expr[start:i].strip())
            start = i + 1
    for part in (p for p in parts if p):
        out += _sequence(part)
    return out


def _sequence(part: str) -> list[str]:
    results = [""]
    for token in re.finditer(r'"((?:[^"\\]|\\.)*)"|\((.*)\)(\?)?', part):
        if token.group(1) is not None:
            results = [r + token.group(1).replace("\\'", "'") for r in results]
        else:
            inner = _expand(token.group(2)) + ([""] if token.group(3) else [])
            results = [r + i for r in results for i in inner]
    return results


def test_the_trie_spells_exactly_the_words():
    words = ["a", "an", "and", "robot", "robot's", "robots", "rotate", "the", "there", "these"]
    assert sorted(_expand(_alternatives(words))) == sorted(words)


def test_the_grammar_allows_the_results_figures_with_their_units_and_supported_claims_only():
    grammar = answer_grammar("how is the battery?", BATTERY, {"charging"})
    assert spelled(grammar, "figure") == {"85.0 %", "85 %", "27.12 V", "4.40 A"}
    assert not re.search(r'"\d', grammar.split("figure ::= ")[0])  # no digit outside figures
    words = spelled(grammar)
    assert {"charging", "battery", "the", "is"} <= words
    assert not words & {"arrived", "reached", "moving", "docked", "error", "person", "pallet"}

    blocked = spelled(answer_grammar("anything in the way?", OBSTACLE, {"obstacles"}, {"pallet"}))
    assert {"pallet", "blocked"} <= blocked and "person" not in blocked
    assert quantities(OBSTACLE) == ["1", "2.4 m", "2 deg"]


def test_an_answer_to_a_commanded_move_opens_by_saying_it_was_commanded():
    results = "ros2 topic pub -t 5 /cmd_vel geometry_msgs/msg/Twist '{linear: {x: 0.3}}'\n  commanded forward 0.30 m/s on /cmd_vel, sent 5 time(s)"
    grammar = answer_grammar("move forward", results, commanded_only=True)
    assert spelled(grammar, "first") == {"Commanded", "Sent"}
    assert "moving" not in spelled(grammar) and "0.30 m/s" in spelled(grammar, "figure")

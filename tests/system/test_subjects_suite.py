"""`astiop bench run --suite questions|watches` in its own process: every question of the suite
right or honestly declined (tests/unit/test_subjects.py: each kind of question, in process), and
every watch read as said."""

import json
import subprocess
import sys

from astiop.bench.library import builtin


def _rules_scores(tmp_path, suite: str) -> dict:
    """`astiop bench run --stage 2 --suite SUITE -m rules --json`: the run's components."""
    out = subprocess.run(
        [sys.executable, "-m", "astiop", "--db", str(tmp_path / "b.db"), "bench", "run",
         "--stage", "2", "--suite", suite, "-m", "rules", "--json"],
        capture_output=True, text=True, check=True, timeout=300,
    )  # fmt: skip
    return json.loads(out.stdout)["results"][0]["components"]


def test_the_questions_suite_scores_rules_with_nothing_answered_else(tmp_path):
    """`astiop bench run --suite questions`: every case right or honestly declined."""
    suite = builtin("questions")
    assert len(suite.cases) >= 60 and len({c.category for c in suite.cases}) >= 9
    comps = _rules_scores(tmp_path, "questions")
    assert comps["questions_other"] == 0, comps
    assert comps["questions_right"] + comps["questions_declined"] == len(suite.cases)


def test_the_watches_suite_scores_rules_right_on_every_case(tmp_path):
    """`astiop bench run --suite watches`: each watch read as said, each one that cannot be
    kept refused in one line, each request that is no watch answered as the robot reports."""
    suite = builtin("watches")
    assert len(suite.cases) >= 20 and sum(c.category == "not_a_watch" for c in suite.cases) >= 5
    comps = _rules_scores(tmp_path, "watches")
    assert comps["questions_right"] == len(suite.cases), comps

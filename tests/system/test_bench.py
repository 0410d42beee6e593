"""The benchmark: the paper's formulas by hand, checks against the sim's truth, whole runs."""

import asyncio
import json
import math

import pytest

from astiop.agent.turn import TurnResult
from astiop.bench import library, runner, scoring
from astiop.bench.report import load_report, to_csv, to_markdown
from astiop.bench.stage2 import Truth, build_sim, check_answer, score_case
from astiop.config import load_settings
from astiop.store import Store
from astiop.transports.base import Execution
from tests.cli_runner import run_cli


# -- Eq. 1-2 and 9-10 against hand-computed values ---------------------------------------
def test_stage1_composite_eq1():
    # 0.35*80 + 0.3*50 + 0.2*100 + 0.15*100 = 28 + 15 + 20 + 15
    assert scoring.stage1_composite(80, 50, 100, 100) == pytest.approx(78.0)


def test_stage1_speed_eq2_normalises_to_the_fastest():
    assert scoring.speed_scores({"a": 50.0, "b": 100.0, "c": 0.0}) == {
        "a": 50.0,
        "b": 100.0,
        "c": 0.0,
    }


def test_stage2_composite_eq9():
    # 0.25*80 + 0.25*60 + 0.3*50 + 0.2*40 = 20 + 15 + 15 + 8
    assert scoring.stage2_composite(80, 60, 50, 40) == pytest.approx(58.0)


def test_stage2_speed_eq10():
    assert scoring.stage2_speed(5.0, 20.0) == pytest.approx(75.0)
    assert scoring.stage2_speed(30.0, 20.0) == 0.0


def test_paper_table_8_reproduces():
    # Gemma3-qat: Q 85.57, C 48.58, Sp 15.99, R 100 -> 62.72 in Table 8
    assert scoring.stage1_composite(85.57, 48.58, 15.99, 100) == pytest.approx(62.72, abs=0.01)


# -- stage-1 per-case quality --------------------------------------------------------------
def test_code_blocks_are_checked_not_counted():
    good = "```python\nimport rclpy\nprint('x')\n```\n```yaml\na: 1\n```\n```xml\n<launch/>\n```"
    bad = "```python\ndef broken(:\n```\n```yaml\na: [\n```"
    assert scoring.check_code(good) == scoring.CodeCheck(3, 3)
    assert scoring.check_code(bad) == scoring.CodeCheck(2, 0)
    assert scoring.code_score(good, "python") == 100 and scoring.code_score(bad, "python") == 50
    assert scoring.code_score("no code", "python") == 0
    assert scoring.code_score("no code", "none") == 100


def test_coverage_accepts_synonyms():
    topics = (("DDS", "data distribution service"), ("QoS", "quality of service"), ("lifecycle",))
    assert scoring.coverage(
        "It uses a Data Distribution Service with quality of service.", topics
    ) == pytest.approx(200 / 3)


def test_quality_formula():
    text = " ".join(["word"] * 80)  # L=100, K=100 (none expected), T=0, C=0
    assert scoring.quality(text, (("absent",),), "none") == pytest.approx(55.0)


# -- stage-2 checks against the simulator's ground truth -----------------------------------
def _case(cid):
    return next(c for c in library.builtin("astiop-stage2").cases if c.id == cid)


def _turn(answer, commands=()):
    t = TurnResult("m", "tool", "q", answer=answer)
    t.commands = [Execution(c, True, executed=True) for c in commands]
    return t


def test_battery_answer_right_passes_wrong_fails(store):
    case = _case("bat02")  # battery 0.42
    sim = build_sim(case, store, seed=0)
    truth = sim.snapshot()
    assert check_answer(case, "The battery is at 42.0 %.", truth) == {"battery": True}
    assert check_answer(case, "The battery is at 0.42.", truth) == {"battery": True}
    assert check_answer(case, "The battery is at 47 %.", truth) == {"battery": False}


def test_position_and_obstacle_answers(store):
    case = _case("obs02")  # two obstacles placed
    sim = build_sim(case, store, seed=0)
    truth = sim.snapshot()
    assert len(truth.detected) == 2
    assert check_answer(case, "Two obstacles: a pallet and a person.", truth)["obstacles"]
    assert not check_answer(case, "One obstacle ahead.", truth)["obstacles"]
    assert not check_answer(case, "No obstacles, the path is clear.", truth)["obstacles"]
    pos = _case("pos03")
    truth = build_sim(pos, store, seed=0).snapshot()
    assert check_answer(pos, "It is at x 20.00, y 12.25.", truth)["position"]
    assert not check_answer(pos, "It is at x 12.00, y 20.25.", truth)["position"]


def test_claimed_arrival_that_did_not_happen_fails(store):
    case = _case("nav01")
    sim = build_sim(case, store, seed=0)
    goto = (
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: assembly_station}"'
    )
    # the model wrote the right command and claims arrival, but the robot never moved
    score = score_case(
        case,
        _turn("The robot has arrived at the assembly station.", [goto]),
        sim.snapshot(),
        Truth.of_sim(sim),
        store,
    )
    assert score.details["outcome"] == {"arrive": False} and not score.c_valid
    # when it really drives there, the same command scores full marks
    sim.goto(8.0, 22.6, math.pi / 2)
    sim.run_goal(300)
    after = Truth.of_sim(sim)
    score = score_case(case, _turn("On its way.", [goto]), sim.snapshot(), after, store)
    assert score.c_valid and score.command == 100


# -- whole runs ------------------------------------------------------------------------------
def _settings(tmp_path):
    return load_settings({"llm": {"threads": 1}}, env={}, path=tmp_path / "none.toml")


@pytest.mark.slow
def test_full_stage2_run_with_rules(store, tmp_path):
    config = runner.RunConfig(stage=2, models=["rules"])
    run_id = runner.create_run(store, config)
    asyncio.run(runner.run(store, _settings(tmp_path), config, run_id))
    rep = load_report(store, run_id)
    (result,) = rep.results
    cases = runner.suite_of(store, config).cases  # the suite the run ran
    assert result.cases == len(cases) >= 90  # each request and its paraphrases
    assert {c.base for c in cases if c.id.endswith(".p2")} == {
        c.id for c in cases if not c.base or c.id == c.base
    }
    assert result.errors == 0 and result.components["wrong_actuations"] == 0
    assert set(result.by_case) == {c.base for c in cases}
    assert "| 1 | rules | rules |" in to_markdown(rep) and "## By case" in to_markdown(rep)
    assert to_csv(rep).count("\n") == result.cases + 1


def test_interrupted_run_keeps_results_and_resumes(store, tmp_path):
    config = runner.RunConfig(stage=2, models=["rules"], limit=6)
    run_id = runner.create_run(store, config)

    def stop_after_three(p):
        if p.done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        asyncio.run(runner.run(store, _settings(tmp_path), config, run_id, stop_after_three))
    assert load_report(store, run_id).status == "interrupted"
    assert load_report(store, run_id).results[0].cases == 3
    again = asyncio.run(
        runner.run(store, _settings(tmp_path), runner.load_config(store, run_id), run_id)
    )
    assert again == 3 and load_report(store, run_id).results[0].cases == 6


def test_suites_meet_the_brief(tmp_path):
    knowledge = library.load_suite("astiop-stage1", tmp_path).cases
    levels = [c.level for c in knowledge]
    assert len(knowledge) >= 40
    for level, least in [
        ("beginner", 5),
        ("intermediate", 6),
        ("advanced", 6),
        ("expert", 6),
        ("troubleshooting", 3),
    ]:
        assert levels.count(level) >= least
    assert len(library.load_suite("astiop-stage2", tmp_path).cases) >= 30


def test_stage2_runs_in_its_own_world_and_records_each_case(tmp_path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    operator = Store(tmp_path / "operator.db")
    operator.remove_location("shipping")  # pos04 starts there: the run must not need this table
    operator.rename_location("inspection_zone_a", "zone_a")
    before = operator.list_locations()
    out = run_cli(
        "--db", str(tmp_path / "operator.db"), "bench", "run", "--stage", "2", "--model", "rules",
        "--limit", "12", "--record", str(tmp_path / "cases"), "--json",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)["results"][0]
    assert result["cases"] == 12 and result["errors"] == 0
    assert operator.list_locations() == before  # the operator's table, untouched
    files = sorted((tmp_path / "cases").glob("*.mcap"))
    assert len(files) == 12 and files[0].name.startswith("run1-rules-rules-")
    with open(tmp_path / "cases" / "run1-rules-rules-pos04.mcap", "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        poses = [msg for *_rest, msg in reader.iter_decoded_messages(["/robot_pose"])]
    assert len(poses) >= 50  # 5 s at 10 Hz of sim time
    assert (round(poses[-1].x, 1), round(poses[-1].y, 1)) == (37.6, 4.0)  # at shipping
    refused = run_cli("--db", str(tmp_path / "operator.db"), "bench", "run", "--stage", "1",
                      "--model", "rules", "--record", str(tmp_path / "x"))  # fmt: skip
    assert refused.returncode == 2 and "stage 2" in refused.stderr


def test_cli_bench_run_json_and_bad_input(tmp_path):
    db = str(tmp_path / "b.db")

    def astiop(*args):
        return run_cli("--db", db, *args)

    out = astiop("bench", "run", "--stage", "2", "--model", "rules", "--limit", "4", "--json")
    data = json.loads(out.stdout)
    assert data["stage"] == 2 and data["results"][0]["cases"] == 4
    assert set(data["results"][0]) == {
        "model",
        "mode",
        "components",
        "composite",
        "cases",
        "errors",
        "timeouts",
    }
    assert "rules" in astiop("bench", "list").stdout
    assert astiop("bench", "report", str(data["run_id"]), "--format", "csv").returncode == 0
    for bad in (
        ["bench", "run", "--stage", "3", "--model", "rules"],
        ["bench", "run", "--stage", "2"],
        ["bench", "run", "--stage", "2", "--model", "nonsense"],
        ["bench", "report", "999"],
        ["bench", "report", "1", "--format", "pdf"],
    ):
        result = astiop(*bad)
        assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1, bad


@pytest.mark.slow
def test_short_run_of_both_stages_with_the_embedded_model(store, tmp_path):
    for stage in (1, 2):
        config = runner.RunConfig(
            stage=stage, models=["embedded"], modes=["tool"], limit=1, max_tokens=48
        )
        run_id = runner.create_run(store, config)
        asyncio.run(runner.run(store, _settings(tmp_path), config, run_id))
        (result,) = load_report(store, run_id).results
        assert result.cases == 1 and result.errors == 0 and result.timeouts == 0
        if stage == 1:
            assert result.components["tokens_per_s"] > 1 and result.components["reliability"] == 100

"""The paper's benchmark: its scripts imported (read, never run), its protocol and scoring, and
every case exported and re-scored here by a second, independent reading of its formulas.

The scripts below are written for these tests in the paper's format; astiop ships none of the
paper's text.
"""

import json
import re
import textwrap

import pytest

from astiop.bench import scoring
from tests.cli_runner import run_cli
from tests.scripted_llm import ScriptedLLM

STAGE1_SCRIPT = textwrap.dedent(
    '''
    import requests
    MODEL_RUNNER_URL = "http://example"
    ROS_EXPERT_SYSTEM_PROMPT = """You answer questions about robots."""
    ROS_TEST_PROMPTS = {
        'beginner': [
            {'category': 'Basics', 'prompt': 'What is a topic?',
             'expected_topics': ['publish', 'subscribe', 'message']},
            {'category': 'Basics', 'prompt': 'What is a node?',
             'expected_topics': ['process', 'graph', 'rclpy', 'executor']},
        ],
        'expert': [
            {'category': 'Security', 'prompt': 'How is DDS secured?',
             'expected_topics': ['certificates', 'encryption', 'permissions']},
        ],
    }
    def run_inference(model, prompt, system_prompt, timeout=300):
        raise SystemExit("never run")
    '''
)
STAGE2_SCRIPT = textwrap.dedent(
    '''
    ROS_COMMAND_AGENT_PROMPT = """You turn requests into ROS 2 commands."""
    TEST_SCENARIOS = {
        'position_queries': [
            {'query': 'Where is it?', 'expected_command_parts': ['ros2', 'topic', 'echo', '/pose'],
             'expected_topics': ['pose'], 'mock_response': 'x: 1.5\\ny: 2.0',
             'expected_interpretation_parts': ['position', 'x', 'y', '1.5', 'robot']},
        ],
        'battery_queries': [
            {'query': 'Battery?', 'expected_command_parts': ['ros2', 'topic', 'echo', '/battery'],
             'expected_topics': ['battery'], 'mock_response': 'percentage: 0.5',
             'expected_interpretation_parts': ['battery', '50', 'percent']},
        ],
    }
    def test_agent_two_stage(model, scenario, system_prompt):
        query = scenario['query']
        mock_response = scenario['mock_response']
        stage1_prompt = f"Asked: '{query}'. Give the command."
        stage2_prompt = f"Asked: '{query}'. The robot said:\\n{mock_response}\\nExplain it."
        return stage1_prompt, stage2_prompt
    '''
)

# Replies chosen to land on each side of every threshold of the paper's rules.
STAGE1_REPLIES = {
    "What is a topic?": "A topic carries each message; nodes publish and subscribe to it. " * 6,
    "What is a node?": "```python\nclass Talker: pass\n```\nA process in the graph.",
    "How is DDS secured?": "Use certificates.",
}
STAGE2_REPLIES = {
    "Asked: 'Where is it?'. Give the command.": "ros2 topic echo /pose --once",
    "Asked: 'Battery?'. Give the command.": "Just check the battery level, please.",
    "Asked: 'Where is it?'. The robot said:\nx: 1.5\ny: 2.0\nExplain it.":
        "The robot position is x 1.5 and y 2.0 on the map right now.",
    "Asked: 'Battery?'. The robot said:\npercentage: 0.5\nExplain it.":
        "ros2 says battery 50",
}  # fmt: skip


@pytest.fixture
def paper_repo(tmp_path):
    repo = tmp_path / "model_runner_web_app"
    repo.mkdir()
    (repo / "test_ros_agents.py").write_text(STAGE1_SCRIPT)
    (repo / "test_ros_command_agent.py").write_text(STAGE2_SCRIPT)
    return repo


@pytest.fixture
def server():
    llm = ScriptedLLM()
    replies = {**STAGE1_REPLIES, **STAGE2_REPLIES}
    llm.default = lambda messages: replies[messages[-1]["content"]]
    yield llm
    llm.close()


def cli(tmp_path, *args):
    return run_cli("--db", str(tmp_path / "bench.db"), "bench", *args)


def test_the_scripts_import_as_suites_without_running(tmp_path, paper_repo):
    out = cli(tmp_path, "import", str(paper_repo / "test_ros_agents.py"),
              str(paper_repo / "test_ros_command_agent.py"))  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert "paper-stage1: stage 1, 3 cases" in out.stdout
    assert "paper-stage2: stage 2, 2 cases" in out.stdout
    listed = json.loads(cli(tmp_path, "suites", "--json").stdout)["suites"]
    by_name = {s["name"]: s for s in listed}
    assert by_name["paper-stage1"]["cases"] == 3 and by_name["paper-stage2"]["kind"] == "mock"
    assert by_name["astiop-stage2"]["cases"] >= 90
    from astiop.bench.library import load_suite

    one = load_suite("paper-stage1", tmp_path)
    assert one.system == "You answer questions about robots."
    assert [c.topics for c in one.cases][1] == (("process",), ("graph",), ("rclpy",), ("executor",))
    two = load_suite("paper-stage2", tmp_path)
    assert two.templates["interpret_prompt"].format(query="q", mock_response="m") == (
        "Asked: 'q'. The robot said:\nm\nExplain it."
    )
    assert two.cases[1].command_parts == ("ros2", "topic", "echo", "/battery")


def test_other_files_are_refused_in_one_line(tmp_path):
    other = tmp_path / "other.py"
    other.write_text("X = 1\n")
    broken = tmp_path / "broken.yaml"
    broken.write_text("name: x\nstage: 3\nsystem: s\n")
    odd = tmp_path / "odd" / "test_ros_agents.py"  # the script's names, not its case format
    odd.parent.mkdir()
    odd.write_text('ROS_EXPERT_SYSTEM_PROMPT = "x"\nROS_TEST_PROMPTS = {"beginner": [1]}\n')
    for path, says in ((other, "not test_ros_agents.py"), (broken, "stage must be 1 or 2"),
                       (odd, "not in the script's format"),
                       (tmp_path / "none.py", "no such file")):  # fmt: skip
        out = cli(tmp_path, "import", str(path))
        assert out.returncode == 2 and says in out.stderr, out.stderr
        assert len(out.stderr.strip().splitlines()) == 1


def test_a_users_own_suite_file_is_imported_by_its_name(tmp_path):
    own = tmp_path / "mine.yaml"
    own.write_text(
        "name: my-ros\nstage: 1\nsystem: Be brief.\nprompts:\n"
        "  - {id: q1, level: beginner, category: basics, prompt: 'What is ROS?', "
        "topics: [[middleware, framework], [nodes]]}\n"
    )
    assert cli(tmp_path, "import", str(own)).returncode == 0
    assert (tmp_path / "suites" / "my-ros.yaml").is_file()
    runs = cli(tmp_path, "run", "--stage", "1", "--suite", "my-ros", "--model", "rules", "--json")
    assert runs.returncode == 0 and json.loads(runs.stdout)["results"][0]["cases"] == 1


def independent_stage1(response, topics):
    """A second reading of test_ros_agents.py's evaluate_response_quality."""
    low = response.lower()
    covered = len([t for t in topics if t.lower() in low])
    coverage = 100.0 * covered / len(topics)
    quality = 0
    for passed in (
        len(response) > 100,
        len(response) > 300,
        any(s in response for s in ("def ", "class ", "```")),
        coverage > 50,
    ):
        quality += 25 if passed else 0  # fmt: skip
    return quality, coverage


def independent_stage2(command, interpretation, cmd_parts, interp_parts):
    """A second reading of test_ros_command_agent.py's two evaluate_* functions."""

    def share(text, parts):
        return 100.0 * len([p for p in parts if p.lower() in text.lower()]) / len(parts)

    c, i = share(command, cmd_parts), share(interpretation, interp_parts)
    low_c, low_i = command.lower(), interpretation.lower()
    c_ok = "ros2" in low_c and re.search("topic|service|node|param", low_c) is not None and c >= 60
    just_command = "ros2" in low_i and low_i.count("ros2") < 2
    i_ok = len(interpretation.split()) > 5 and not just_command and i >= 40
    return c, c_ok, i, i_ok


def test_a_paper_run_exports_every_case_and_rescoring_agrees(tmp_path, paper_repo, server):
    cli(tmp_path, "import", str(paper_repo / "test_ros_agents.py"),
        str(paper_repo / "test_ros_command_agent.py"))  # fmt: skip
    model = f"openai:scripted-model@{server.url}"
    for stage in ("1", "2"):
        out = cli(tmp_path, "run", "--stage", stage, "--protocol", "paper",
                  "--suite", f"paper-stage{stage}", "--model", model, "--json")  # fmt: skip
        assert out.returncode == 0, out.stderr
    assert all(r["stream"] is False and "max_tokens" not in r and "temperature" not in r
               for r in server.requests)  # the scripts' request, exactly  # fmt: skip
    assert len(server.requests) == 3 + 2 * 2  # stage 2: two independent calls per scenario
    cases = [json.loads(line) for line in cli(tmp_path, "report", "1", "--format",
                                              "jsonl").stdout.splitlines()]  # fmt: skip
    assert len(cases) == 3
    qs, cs = [], []
    for case in cases:
        assert case["response"] == STAGE1_REPLIES[case["prompt"]]
        q, c = independent_stage1(case["response"], case["expected_topics"])
        assert (case["quality_score"], case["coverage_score"]) == pytest.approx((q, c), abs=0.01)
        assert case["tokens_per_sec"] == pytest.approx(case["tokens"] / case["total_time"])
        qs.append(q)
        cs.append(c)
    assert qs == [75, 25, 0]  # long, no code, 2/3 topics | short, code, 2/4 (not > 50) | short
    report = json.loads(cli(tmp_path, "report", "1", "--format", "json").stdout)
    (row,) = report["results"]
    assert row["components"]["quality"] == pytest.approx(sum(qs) / 3, abs=0.01)
    assert row["components"]["coverage"] == pytest.approx(sum(cs) / 3, abs=0.01)
    assert row["components"]["reliability"] == 100
    csv_text = cli(tmp_path, "report", "2", "--format", "csv").stdout
    header = csv_text.splitlines()[0].split(",")
    for field in (
        "model",
        "category",
        "query",
        "command_response",
        "command_valid",
        "command_score",
        "mock_data",
        "interpretation_response",
        "interpretation_valid",
        "interpretation_score",
        "status",
        "stage",
        "total_time",
        "total_tokens",
        "error",
    ):  # the paper's CSV, and more
        assert field in header or (field == "query" and "prompt" in header), field
    two = json.loads(cli(tmp_path, "report", "2", "--format", "json").stdout)
    both = 0
    for case in two["cases"]:
        c, c_ok, i, i_ok = independent_stage2(
            case["command_response"], case["interpretation_response"],
            case["expected_command_parts"], case["expected_interpretation_parts"])  # fmt: skip
        assert (case["command_score"], case["command_valid"]) == (pytest.approx(c), c_ok)
        assert (case["interpretation_score"], case["interpretation_valid"]) == (
            pytest.approx(i), i_ok)  # fmt: skip
        both += c_ok and i_ok
    assert [(c["command_valid"], c["interpretation_valid"]) for c in two["cases"]] == [
        (True, True), (False, False)]  # fmt: skip
    (row2,) = two["results"]
    assert row2["components"]["both_valid"] == pytest.approx(100 * both / 2)
    md = cli(tmp_path, "report", "2").stdout
    assert "## Ranking, the paper's protocol (Eq. 9)" in md and "| Both valid |" in md


def test_table_8_components_give_its_composites_with_r_100():
    table8 = {  # model: (Q, C, Sp, composite)
        "Gemma3-qat": (85.57, 48.58, 15.99, 62.72),
        "Gemma3": (84.61, 47.62, 16.03, 62.11),
        "SmolLM2": (62.5, 14.48, 86.04, 58.42),
        "Llama 3.2": (80.76, 34.74, 18.35, 57.36),
    }
    for model, (q, c, sp, s) in table8.items():
        # 0.35 Q + 0.3 C + 0.2 Sp + 0.15 R, with R = 100 (every test succeeded)
        assert 0.35 * q + 0.3 * c + 0.2 * sp + 0.15 * 100 == pytest.approx(s, abs=0.01), model
        assert scoring.stage1_composite(q, c, sp, 100) == pytest.approx(s, abs=0.01)
        assert round(q * 26) % 25 == 0  # a mean of 26 per-case scores that step by 25
    # Sp: the fastest model (SmolLM2) is at 86.04, not 100 - so not normalised to the fastest
    # model's mean; against the fastest single test of the run it can be (Eq. 2 as read here)
    assert scoring.speed_scores({"smollm2": 50.0, "gemma3": 9.3})["smollm2"] == 100
    assert scoring.paper_speed(86.04, 100.0) == pytest.approx(86.04)
    assert scoring.paper_speed(120.0, 100.0) == 100  # capped


def test_protocols_and_suites_that_do_not_fit_are_refused(tmp_path, paper_repo):
    cli(tmp_path, "import", str(paper_repo / "test_ros_command_agent.py"))
    for args, says in (
        (["--stage", "2", "--protocol", "paper", "--model", "embedded"], "has none"),
        (["--stage", "2", "--suite", "paper-stage2", "--model", "embedded"], "--protocol paper"),
        (["--stage", "1", "--protocol", "paper", "--model", "rules"], "rules has none"),
        (["--stage", "2", "--protocol", "both", "--model", "embedded"], "for stage 1"),
        (["--stage", "1", "--suite", "paper-stage2", "--model", "embedded"], "stage-2 suite"),
        (["--stage", "1", "--suite", "nowhere", "--model", "embedded"], "no suite named"),
    ):
        out = cli(tmp_path, "run", *args)
        assert out.returncode == 2 and says in out.stderr, (args, out.stderr)


@pytest.mark.slow
def test_figures_are_image_files_with_the_runs_numbers(tmp_path, paper_repo, server):
    import xml.etree.ElementTree as ET

    from matplotlib.image import imread

    cli(tmp_path, "import", str(paper_repo / "test_ros_agents.py"),
        str(paper_repo / "test_ros_command_agent.py"))  # fmt: skip
    model = f"openai:scripted-model@{server.url}"
    for stage in ("1", "2"):
        cli(tmp_path, "run", "--stage", stage, "--protocol", "paper",
            "--suite", f"paper-stage{stage}", "--model", model)  # fmt: skip
    for run, names in (
        ("1", ("fig07-bars", "fig08-reliability", "fig09-quality-by-category", "fig10-radar",
               "fig11-ranking")),
        ("2", ("fig12-bars", "fig08-reliability", "fig13-by-category", "fig14-radar",
               "fig15-ranking")),
    ):  # fmt: skip
        out = cli(tmp_path, "report", run, "--figures", str(tmp_path / "figs"), "--format", "json")
        assert out.returncode == 0, out.stderr
        composite = json.loads(out.stdout)["results"][0]["composite"]
        for name in names:
            png = imread(tmp_path / "figs" / f"run{run}-{name}.png")
            assert png.shape[0] > 200 and png.shape[1] > 300
            svg = (tmp_path / "figs" / f"run{run}-{name}.svg").read_text()
            ET.fromstring(svg)  # well-formed
            assert "scripted-model" in svg, name
        ranking = (tmp_path / "figs" / f"run{run}-{names[-1]}.svg").read_text()
        assert f"{composite:.2f}" in ranking  # the run's own composite, drawn


def test_without_matplotlib_figures_are_one_line(tmp_path, paper_repo, server, monkeypatch):
    import builtins

    real = builtins.__import__

    def no_matplotlib(name, *args, **kwargs):
        if name.startswith("matplotlib"):
            raise ImportError(name)
        return real(name, *args, **kwargs)

    cli(tmp_path, "run", "--stage", "2", "--model", "rules", "--limit", "1")
    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    out = cli(tmp_path, "report", "1", "--figures", str(tmp_path / "figs"))
    assert out.returncode == 2 and 'pip install "astiop[plots]"' in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1

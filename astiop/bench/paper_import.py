"""The paper's benchmark suites, read from the user's copy of its repository
(mihaidanielPavel/model_runner_web_app): `test_ros_agents.py` (stage 1) and
`test_ros_command_agent.py` (stage 2).

The scripts are parsed with `ast`, never executed or imported: only literal module-level
assignments are read, and the two user prompts of stage 2 from the f-strings the script builds
them with. astiop ships none of this text; it writes it to the user's data dir.
"""

from __future__ import annotations

import ast
import contextlib
import gc
from pathlib import Path
from typing import Any

import yaml

from astiop.bench.library import (
    NAME_RE,
    Suite,
    parse_suite,
    read_suite_file,
    suite_data,
    suites_dir,
)
from astiop.bench.suites import SuiteError

STAGE1 = ("ROS_EXPERT_SYSTEM_PROMPT", "ROS_TEST_PROMPTS")
STAGE2 = ("ROS_COMMAND_AGENT_PROMPT", "TEST_SCENARIOS")
STAGE2_PROMPTS = {"stage1_prompt": "command_prompt", "stage2_prompt": "interpret_prompt"}
REPO = "mihaidanielPavel/model_runner_web_app"


def _literals(tree: ast.Module) -> dict[str, Any]:
    """Module-level `NAME = <literal>` assignments; anything else is skipped, not run."""
    found = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1:
            target = node.targets[0]
            if isinstance(target, ast.Name):
                with contextlib.suppress(ValueError, TypeError, SyntaxError, RecursionError):
                    found[target.id] = ast.literal_eval(node.value)
    return found


def _template(node: ast.JoinedStr) -> str | None:
    """An f-string whose fields are plain names, as a str.format template."""
    parts = []
    for value in node.values:
        if isinstance(value, ast.Constant) and isinstance(value.value, str):
            parts.append(value.value.replace("{", "{{").replace("}", "}}"))
        elif (
            isinstance(value, ast.FormattedValue)
            and isinstance(value.value, ast.Name)
            and value.conversion == -1
            and value.format_spec is None
        ):
            parts.append("{" + value.value.id + "}")
        else:
            return None
    return "".join(parts)


def _prompt_templates(tree: ast.Module) -> dict[str, str]:
    found = {}
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
            and node.targets[0].id in STAGE2_PROMPTS
            and isinstance(node.value, ast.JoinedStr)
        ):
            text = _template(node.value)
            if text is not None:
                found[STAGE2_PROMPTS[node.targets[0].id]] = text
    return found


def _parse(source: str, filename: str) -> ast.Module:
    # CPython 3.11.7: a collection that runs finalizers mid-parse can break ast's recursion
    # check ("AST constructor recursion depth mismatch"); hold the collector off meanwhile.
    enabled = gc.isenabled()
    gc.disable()
    try:
        return ast.parse(source, filename=filename)
    finally:
        if enabled:
            gc.enable()


def paper_suite(path: Path) -> dict[str, Any]:
    """The suite data of one of the paper's two scripts; SuiteError for any other file."""
    try:
        source = Path(path).read_text(encoding="utf-8")
        tree = _parse(source, str(path))
    except (OSError, UnicodeDecodeError) as exc:
        raise SuiteError(f"cannot read {path}: {getattr(exc, 'strerror', None) or exc}") from None
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        raise SuiteError(f"{path}: not a Python file astiop can read ({exc})") from None
    names = _literals(tree)
    source_text = f"{Path(path).name} of {REPO}, imported by astiop"
    try:
        if all(k in names for k in STAGE1):
            return _stage1(names, source_text, path)
        if all(k in names for k in STAGE2):
            templates = _prompt_templates(tree)
            if set(templates) != set(STAGE2_PROMPTS.values()):
                raise SuiteError(f"{path}: the two stage-2 prompts (stage1_prompt, "
                                 "stage2_prompt) were not found as f-strings")  # fmt: skip
            return _stage2(names, templates, source_text, path)
    except (KeyError, TypeError, AttributeError) as exc:  # a case without the script's fields
        raise SuiteError(f"{path}: a case is not in the script's format ({exc!r})") from None
    raise SuiteError(
        f"{path}: not test_ros_agents.py or test_ros_command_agent.py of {REPO} "
        f"(it assigns neither {STAGE1[1]} nor {STAGE2[1]}), nor an astiop suite"
    )


def _levels(value: Any, path: Path, what: str) -> dict[str, list[dict]]:
    if not isinstance(value, dict) or not all(isinstance(v, list) for v in value.values()):
        raise SuiteError(f"{path}: {what} is not a mapping of lists")
    return value


def _stage1(names: dict, source: str, path: Path) -> dict[str, Any]:
    prompts = []
    for level, items in _levels(names[STAGE1[1]], path, STAGE1[1]).items():
        for k, item in enumerate(items, 1):
            prompts.append(
                {
                    "id": f"{level}-{k:02d}",
                    "level": level,
                    "category": item.get("category", level),
                    "prompt": item["prompt"],
                    "topics": [[t] for t in item.get("expected_topics", [])],  # as the script
                    "code": "none",
                }
            )
    return {
        "name": "paper-stage1",
        "stage": 1,
        "source": source,
        "system": names[STAGE1[0]],
        "prompts": prompts,
    }


def _stage2(names: dict, templates: dict, source: str, path: Path) -> dict[str, Any]:
    scenarios = []
    for category, items in _levels(names[STAGE2[1]], path, STAGE2[1]).items():
        for k, item in enumerate(items, 1):
            scenarios.append(
                {
                    "id": f"{category}-{k:02d}",
                    "category": category,
                    "request": item["query"],
                    "command_parts": list(item["expected_command_parts"]),
                    "mock_response": item["mock_response"],
                    "interpretation_parts": list(item["expected_interpretation_parts"]),
                }
            )
    return {
        "name": "paper-stage2",
        "stage": 2,
        "source": source,
        "system": names[STAGE2[0]],
        **templates,
        "scenarios": scenarios,
    }


def import_suite(path: Path, data_dir: Path) -> tuple[Suite, Path]:
    """Read one of the paper's scripts or an astiop suite file, check it, and keep it as
    <data dir>/suites/NAME.yaml (replacing an earlier import of that name)."""
    path = Path(path).expanduser()
    if not path.is_file():
        raise SuiteError(f"{path}: no such file")
    if path.suffix == ".py":
        data = paper_suite(path)
        try:
            suite = parse_suite(data, str(path))
        except SuiteError as exc:
            raise SuiteError(
                f"{path}: the script's cases are not what astiop expects: {exc}"
            ) from None
    else:
        data = suite_data(path)
        suite = parse_suite(data, str(path), str(path))
    if suite.name in ("astiop-stage1", "astiop-stage2") or not NAME_RE.match(suite.name):
        raise SuiteError(f"{path}: the name '{suite.name}' is taken by a built-in suite")
    out = suites_dir(data_dir) / f"{suite.name}.yaml"
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        text = yaml.safe_dump(data, sort_keys=False, allow_unicode=True, width=100)
        out.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise SuiteError(f"cannot write {out}: {exc.strerror or exc}") from None
    return read_suite_file(out), out

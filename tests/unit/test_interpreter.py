"""The agent's interpreter built alone (no `Agent`, no model server): who answers a turn's
results, what the model is asked, and how its answer is held to what the robot reported."""

import pytest

from astiop.agent.interpretation import Interpreter
from astiop.agent.models.reply_stream import Completion
from astiop.agent.models.specs import open_endpoint
from astiop.agent.result import TurnResult
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.transports.base import Execution
from astiop.transports.simulator.backend import SimBackend

REQUEST = "what is the battery level?"
REMOTE = open_endpoint("openai:scripted@http://127.0.0.1:9/v1")  # never reached: asked by `ask`


class Ask:
    """The agent's `_ask` as the interpreter sees it: each call recorded, a written reply."""

    def __init__(self, *replies: str, finish_reason: str = "stop"):
        self.replies = list(replies)
        self.finish_reason = finish_reason
        self.calls: list[dict] = []

    async def __call__(self, messages, schema, result, emit, kind, grammar=None, max_tokens=None):
        self.calls.append(
            {"messages": messages, "schema": schema, "kind": kind, "grammar": grammar,
             "max_tokens": max_tokens}
        )  # fmt: skip
        text = self.replies.pop(0)
        emit(kind, text)
        return Completion(text, 0.01, 0.02, finish_reason=self.finish_reason)


@pytest.fixture(scope="module")
def battery():
    """A real battery read of a seeded simulator, and its percentage as its summary says it."""
    sim = Simulator(seed=3, start=(8.0, 8.75, 0.0), battery_soc=0.62)
    gateway = RobotGateway(SimBackend(sim, None), SafetyPolicy())
    ex = gateway.run("ros2 topic echo /battery_status --once")
    assert ex.executed and not ex.error
    return ex, f"{ex.values['percentage'] * 100:.1f} %"


def _turn(*commands: Execution) -> TurnResult:
    return TurnResult("scripted", "command", REQUEST, commands=list(commands))


async def _interpret(interpreter, endpoint, result, fallback=""):
    said: list[tuple[str, str]] = []
    answer = await interpreter.interpret(
        endpoint, REQUEST, result, lambda kind, text: said.append((kind, text)), fallback
    )
    return answer, said


async def test_the_rules_answer_without_asking_the_model(battery):
    ex, percent = battery
    ask = Ask()
    result = _turn(ex)
    answer, said = await _interpret(Interpreter(ask), open_endpoint("rules"), result)
    assert percent in answer and result.grounding == "rules" and ask.calls == []
    assert said == [("answer_token", answer)]
    labelled, _ = await _interpret(Interpreter(ask), REMOTE, _turn(ex), "[rules fallback] ")
    assert labelled.startswith("[rules fallback] ") and ask.calls == []


async def test_nothing_ran_is_said_as_the_reason_not_asked_of_the_model():
    refused = Execution("ros2 topic echo /nowhere --once", False, "no such topic")
    ask = Ask()
    result = _turn(refused)
    answer, _ = await _interpret(Interpreter(ask), REMOTE, result)
    assert result.grounding == "nothing ran" and ask.calls == [] and answer


async def test_a_grounded_answer_is_kept_and_asked_for_within_its_tokens(battery):
    ex, percent = battery
    ask = Ask(f"The battery is at {percent}.")
    result = _turn(ex)
    answer, said = await _interpret(Interpreter(ask, max_tokens=40), REMOTE, result)
    assert answer == f"The battery is at {percent}." and result.grounding == "kept"
    (call,) = ask.calls
    assert call["kind"] == "answer_token" and call["max_tokens"] == 40
    assert call["schema"] is None and call["grammar"] is None  # no GBNF for a remote server
    assert percent in call["messages"][-1]["content"]  # the results, as the robot said them
    assert result.model_answer == answer and said == [("answer_token", answer)]


async def test_a_claim_the_results_do_not_hold_is_replaced_unless_raw(battery):
    ex, percent = battery
    wrong = "The battery is at 7 %."
    result = _turn(ex)
    answer, said = await _interpret(Interpreter(Ask(wrong)), REMOTE, result)
    assert result.grounding.startswith("replaced: ") and percent in answer
    assert said[-1] == ("answer_replaced", answer) and result.model_answer == wrong
    raw = _turn(ex)
    answer, _ = await _interpret(Interpreter(Ask(wrong), style="raw"), REMOTE, raw)
    assert answer == wrong and raw.grounding == "raw"


async def test_a_cut_reply_is_replaced_and_a_local_model_gets_the_answer_grammar(battery):
    ex, percent = battery
    ask = Ask(f"The battery is at {percent}", finish_reason="length")
    result = _turn(ex)
    answer, _ = await _interpret(Interpreter(ask), open_endpoint("embedded"), result)
    assert result.grounding.startswith("replaced: the reply was cut") and percent in answer
    grammar = ask.calls[0]["grammar"]
    assert isinstance(grammar, str) and grammar.startswith("root")


def test_an_unknown_style_is_refused():
    with pytest.raises(ValueError, match="'grounded' or 'raw', not 'free'"):
        Interpreter(Ask(), style="free")

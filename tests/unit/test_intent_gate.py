"""The request's intent read without a model, and the gate that holds every plan to it."""

import pytest

from astiop.agent import rules
from astiop.agent.gate import action_of, check
from astiop.agent.intent import classify
from astiop.agent.models.specs import open_endpoint
from astiop.ros2.catalog import astibot_catalog
from astiop.ros2.validation import validate
from astiop.store import Store
from benchmarks.agent_requests import load_requests, run_one
from tests.unit.test_rules import GOTO, LOCS

PLACES = {
    "charging_dock": (2.5, 3.0),
    "assembly_station": (8.0, 22.6),
    "cps_storage": (37.6, 21.0),
    "shipping": (37.6, 4.0),
    "inspection_zone_a": (15.0, 3.5),
    "inspection_zone_b": (25.0, 21.0),
}
TRIGGER = "std_srvs/srv/Trigger"

# phrasings per intent; the pairs that differ by one word sit side by side on purpose
INTENTS = [
    ("Dock the robot", "dock"),
    ("Undock the robot", "undock"),
    ("Go charge", "dock"),
    ("Start charging", "dock"),
    ("Stop charging", "undock"),
    ("Leave the dock", "undock"),
    ("Get off the charger", "undock"),
    ("Return to the dock", "dock"),
    ("Load the conveyor", "load"),
    ("Unload the conveyor", "unload"),
    ("Pick up the pallet", "load"),
    ("Drop off the pallet", "unload"),
    ("Stop the robot", "stop"),
    ("Start moving forward", "motion"),
    ("Cancel the current mission", "stop"),
    ("Halt!", "stop"),
    ("Can you stop please?", "stop"),
    ("Is the robot docked?", "read"),
    ("Is it loaded?", "read"),
    ("Why did it stop?", "read"),
    ("How much charge is left?", "read"),
    ("Report the current charge percentage", "read"),
    ("Send the robot to the assembly station", "navigate"),
    ("Could you send it to shipping?", "navigate"),
    ("Save this spot as inspection_point_c", "save"),
    ("Remember this position as bay_7", "save"),
    ("Which locations do you know?", "list"),
    ("Move forward slowly", "motion"),
    ("Rotate in place to the left", "motion"),
    ("Strafe right a little", "motion"),
    ("Back up a bit", "motion"),
    ("Don't move the robot", "none"),
    ("Tell me a joke", "read"),
    ("Sing a song", "unknown"),
    ("Set the max speed to 0.5", "configure"),
]


@pytest.mark.parametrize("text,kind", INTENTS)
def test_intent_of_a_phrasing(text, kind):
    assert [i.kind for i in classify(text, LOCS)] == [kind]


READ = "ros2 topic echo {} --once"
RULES = [
    ("Leave the dock", [f"ros2 service call /undock {TRIGGER}"]),
    ("Start charging", [f"ros2 service call /dock {TRIGGER}"]),
    ("how much juice is left", [READ.format("/battery_status")]),
    ("Report the current charge percentage", [READ.format("/battery_status")]),
    ("What's the battery voltage?", [READ.format("/battery_status")]),
    ("How fast is the robot going?", [READ.format("/odom")]),
    ("what is its speed", [READ.format("/odom")]),
    ("Is it carrying anything?", [READ.format("/conveyor/status")]),
    ("Any motor faults?", [READ.format("/diagnostics")]),
    (
        "Which locations are saved?",
        ["ros2 service call /list_locations astiop_msgs/srv/ListLocations"],
    ),
    (
        "Save this spot as inspection_point_c",
        [
            "ros2 service call /save_location astiop_msgs/srv/SaveLocation "
            "\"{name: 'inspection_point_c', description: 'saved by the operator'}\""
        ],
    ),
    ("Cancel the current mission", [f"ros2 service call /stop {TRIGGER}"]),
    ("Drive to shipping", [f"{GOTO} \"{{name: 'shipping'}}\""]),
    ("Go to x 12.5, y 4 facing 90", [f'{GOTO} "{{x: 12.500, y: 4.000, theta: 1.5708}}"']),
    ("Sing a song", []),
    ("Drive to the loading bay", []),  # a place it does not know: no guess
]


@pytest.mark.parametrize("text,expected", RULES)
def test_rules_cover_the_catalog(text, expected):
    assert rules.plan(text, LOCS) == expected


MOTIONS = [
    ("Move forward slowly", (1, 0, 0)),
    ("Drive forward", (1, 0, 0)),
    ("Back up a bit", (-1, 0, 0)),
    ("Strafe left", (0, 1, 0)),
    ("Strafe right a little", (0, -1, 0)),
    ("Rotate in place to the left", (0, 0, 1)),
    ("Turn right", (0, 0, -1)),
]


def _sign(v):
    return (v > 0) - (v < 0)


@pytest.mark.parametrize("text,signs", MOTIONS)
def test_rules_motion_is_short_bounded_and_in_the_asked_direction(text, signs):
    (command,) = rules.plan(text, LOCS)
    checked = validate(command, astibot_catalog())
    assert checked.valid, checked.reason
    action = action_of(checked)
    assert tuple(_sign(v) for v in action.twist) == signs
    assert max(abs(v) for v in action.twist[:2]) <= 0.3 and abs(action.twist[2]) <= 0.6
    slow = "slowly" in text or "little" in text or "bit" in text
    assert max(abs(v) for v in action.twist) <= (0.3 if slow else 0.6)


def gate(request, *commands):
    catalog = astibot_catalog()
    actions = [(c, action_of(validate(c, catalog))) for c in commands]
    return check(classify(request, list(PLACES)), actions, PLACES)


STOP = f"ros2 service call /stop {TRIGGER}"
ZERO = "ros2 topic pub --once /cmd_vel geometry_msgs/msg/Twist '{}'"
GATE = [
    # the wrong actuations the embedded model made on the held-out requests
    ("Cancel the current mission", [f"{GOTO} \"{{name: 'cps_storage'}}\""], "asks to stop"),
    ("Save this spot as inspection_point_c", [f"{GOTO} \"{{name: 'inspection_zone_a'}}\""], "save"),
    ("Drive to shipping", [f'{GOTO} "{{x: 12.5, y: 4.0, theta: 0.0}}"'], "go to shipping"),
    ("Leave the dock", [f"ros2 service call /dock {TRIGGER}"], "undock"),
    ("Strafe right a little", [STOP], "move"),
    # questions never actuate
    ("Is anything blocking the robot?", [f"ros2 service call /dock {TRIGGER}"], "question"),
    ("Where is the robot?", [READ.format("/robot_pose"), STOP], "question"),
    ("Don't move the robot", [f"{GOTO} \"{{name: 'shipping'}}\""], "not to"),
    # a stop yields only a stop
    ("Stop the robot", [STOP, READ.format("/robot_pose")], "only to stop"),
    # the opposite direction
    (
        "Strafe right a little",
        ["ros2 topic pub -t 10 -r 10 /cmd_vel geometry_msgs/msg/Twist '{linear: {y: 0.2}}'"],
        "move",
    ),
    ("Load the conveyor", [f"ros2 service call /conveyor/unload {TRIGGER}"], "load the conveyor"),
    ("Drive to the loading bay", [f"{GOTO} \"{{name: 'shipping'}}\""], "does not know"),
    ("Where is it?", ["ros2 param set /astibot_base max_linear_speed 1.4"], "question"),
    (
        "Set the max speed to 0.5",
        ["ros2 param set /astibot_base max_angular_speed 0.5"],
        "max_linear_speed",
    ),
    ("Start charging", [f"{GOTO} \"{{name: 'charging_dock'}}\""], "asks to dock"),  # not docking
]


@pytest.mark.parametrize("request_text,plan,reason", GATE)
def test_gate_refuses_a_plan_that_does_not_do_what_was_asked(request_text, plan, reason):
    refused = gate(request_text, *plan)
    assert refused is not None and reason in refused


RELEASE = f"ros2 service call /release {TRIGGER}"


@pytest.mark.parametrize("text", [t for t, _ in INTENTS])
def test_release_is_the_operators_never_the_models(text):
    """The robot's /release lets a held robot move again: no request's plan may call it, and
    the model is never told of it (its prompt, its tools); the catalog has it."""
    from astiop.agent.prompts import command_prompt, tool_prompt
    from astiop.agent.tools import build_tools

    catalog = astibot_catalog()
    assert catalog.services["/release"].actuating
    refused = gate(text, RELEASE)
    assert refused is not None and RELEASE in refused
    tools = build_tools(catalog, LOCS)
    assert not [t for t in tools if "/release" in (t.command or "") or "release" in t.id]
    assert "/release" not in command_prompt(catalog, LOCS) + tool_prompt(tools)


PASS = [
    ("Cancel the current mission", [STOP, ZERO]),
    ("Drive to shipping", [f'{GOTO} "{{x: 37.6, y: 4.0, theta: 0.0}}"']),
    ("Drive to shipping", [f"{GOTO} \"{{name: 'shipping'}}\""]),
    (
        "Drive to shipping",
        [
            "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
            '"{pose: {header: {frame_id: map}, pose: {position: {x: 37.5, y: 4.1}}}}"'
        ],
    ),
    ("Where is the robot?", [READ.format("/robot_pose"), READ.format("/odom")]),
    (
        "Go to shipping then unload",
        [f"{GOTO} \"{{name: 'shipping'}}\"", f"ros2 service call /conveyor/unload {TRIGGER}"],
    ),
    (
        "Rotate in place to the left",
        ["ros2 topic pub -t 10 -r 10 /cmd_vel geometry_msgs/msg/Twist '{angular: {z: 0.5}}'"],
    ),
    ("Where is it? Then stop", [READ.format("/robot_pose"), STOP]),
]


@pytest.mark.parametrize("request_text,plan", PASS)
def test_gate_passes_a_plan_that_does_what_was_asked(request_text, plan):
    assert gate(request_text, *plan) is None


@pytest.mark.parametrize("text", [t for t, _ in INTENTS + RULES])
def test_the_rules_plan_always_passes_the_gate(text):
    assert gate(text, *rules.plan(text, LOCS)) is None


async def test_the_rules_on_the_held_out_requests_are_right_without_wrong_actuations(tmp_path):
    """The held-out set of benchmarks/agent_requests.py, run through a real turn on seeded
    simulators with confirmation off: the rules must name the right command for ≥ 90% and
    never run an actuation the request did not ask for."""
    store = Store(tmp_path / "held-out.db")
    endpoint = open_endpoint("rules")
    rows = [await run_one(c, endpoint, "tool", "grounded", store) for c in load_requests()]
    assert len(rows) >= 30
    right = sum(r["right"] and not r["wrong_actuations"] for r in rows)
    assert right >= 0.9 * len(rows), [r["request"] for r in rows if not r["right"]]
    assert not [r for r in rows if r["wrong_actuations"]]
    assert all(r["answer_true"] and not r["loops"] and not r["unsupported"] for r in rows)


NARROW = [
    ("How much juice is left?", {"read"}),
    ("Leave the dock", {"undock"}),
    ("Go to shipping then unload", {"navigate", "unload"}),
    ("Save this spot as bay_2", {"save"}),
    ("Strafe left", {"motion"}),
    ("Which places do you know?", {"list"}),
    ("Sing a song", None),  # unknown: every tool is offered
]


@pytest.mark.parametrize("text,kinds", NARROW)
def test_the_model_is_offered_the_tools_of_the_requests_intent(text, kinds):
    from astiop.agent.tools import build_tools, narrow, tool_grammar

    tools = build_tools(astibot_catalog(), LOCS)
    offered = narrow(tools, classify(text, LOCS))
    assert {t.kind for t in offered} == (kinds or {t.kind for t in tools})
    grammar = tool_grammar(offered)
    ids = {t.id for t in offered}
    assert ("name ::=" in grammar) == bool(ids - {"drive_xy", "save_here"})
    assert ("drive_xy" in grammar) == ("drive_xy" in ids)
    assert ("save_here" in grammar) == ("save_here" in ids)

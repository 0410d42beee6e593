"""A role is one definition (astiop.ros2.roles): the agent's reader, tools, labels and summaries,
the subjects' fields and the live state's names are all read from it, never kept beside it."""

import re

from astiop.agent import intent, subject, summaries, tools
from astiop.agent.roles import KEY_ROLES, STANDS_IN, WHAT, name_for
from astiop.ros2.roles import ROLE_BY_NAME, ROLES, TF_ROLES
from astiop.transports.base import Execution
from astiop.transports.state import ASTIBOT_NAMES


def test_every_read_role_is_keyed_labelled_and_worded_from_its_definition():
    read = [r for r in ROLES if r.label]
    assert {r.name for r in read} >= {"battery", "pose", "scan", "status", "camera"}
    for r in read:
        assert KEY_ROLES[r.key] == r.name and WHAT[r.name] == r.label
        if r.words:
            assert (r.words, r.key) in intent.READS
        if r.tool:
            assert tools.ROLE_TOOLS[r.name] == tools.TOPIC_TOOLS[r.key] == r.tool
        if not r.readable:
            assert r.name in tools.UNREADABLE_ROLES
    assert STANDS_IN == {"obstacles": "scan"}


def test_the_reader_tries_the_more_specific_roles_first():
    ranks = [next(r.rank for r in ROLES if r.key == key) for _, key in intent.READS]
    assert ranks == sorted(ranks)
    # "is the conveyor stopped?" is the conveyor's, not the status's ("stop"); a picture is the
    # camera's, not the obstacles' ("detect")
    assert intent.classify("is the conveyor stopped?", [])[0].topic == "/conveyor/status"
    assert intent.classify("what does the camera detect?", [])[0].topic == "/camera/image_raw"


def test_the_state_watches_the_state_roles_by_the_astibots_names():
    assert set(ASTIBOT_NAMES) == {r.name for r in ROLES if r.state}
    assert all(ASTIBOT_NAMES[r] == "" for r in TF_ROLES)
    assert ASTIBOT_NAMES["battery"] == "/battery_status"


def test_the_fields_an_operator_asks_about_are_the_roles_own():
    for r in ROLES:
        for field, words in r.fields:
            assert subject.FIELDS[(r.name, field)] == words
            re.compile(words)
    assert subject.FIELDS.keys() == {(r.name, f) for r in ROLES for f, _ in r.fields}
    assert list(subject.FIELDS)[-1] == ("status", "docked")  # a heading asked on the dock


def test_a_role_summarised_by_its_templates_says_its_size_not_its_content():
    ex = Execution(
        "ros2 topic echo /camera/image_raw --once",
        True,
        executed=True,
        values={"width": 4, "height": 3, "encoding": "rgb8", "data": [0] * 36},
        role="camera",
    )
    assert summaries.summarize(ex).endswith("camera image 4 x 3 px, rgb8, 36 bytes")
    ex.values = {"format": "", "data_bytes": 1200}
    assert summaries.summarize(ex).endswith("camera image, compressed (not said), 1200 bytes")
    assert ROLE_BY_NAME["camera"].sized == ("data",)


def test_a_robot_names_a_role_by_its_profile_else_none():
    class Profile:
        def name(self, role):
            return {"battery": "/battery_state"}.get(role)

    assert name_for("/battery_status", Profile()) == "/battery_state"
    assert name_for("/camera/image_raw", Profile()) is None
    assert name_for("/camera/image_raw", None) == "/camera/image_raw"

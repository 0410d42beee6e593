"""What the robot sees: a question about its view on a model that takes images sends the camera
frame the robot published (checked pixel by pixel against the simulator's own frame, decoded
from the request a scripted image-taking server received over real HTTP); on a model that cannot
see, one line says so and the lidar answers."""

from __future__ import annotations

import base64
import io
import math
import re

import numpy as np
import pytest
from PIL import Image

from astiop.agent import intent, subject
from astiop.agent.models.specs import open_endpoint
from astiop.agent.turn import Agent
from astiop.config import load_settings
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import SafetyPolicy
from astiop.sim.simulator import Simulator
from astiop.transports.simulator.backend import SimBackend
from tests.scripted_llm import ScriptedLLM

# 2.95 m from the charging station (green), turned 17° from it: the station on the frame's left
DOCK_LEFT = (4.0, 3.0, math.pi - 0.3)
SEEN = "A green charging station stands on the left, a grey wall to the right."


@pytest.fixture
def llm():
    s = ScriptedLLM("openai")
    yield s
    s.close()


def agent_on(sim: Simulator, store, spec: str, vision: bool) -> Agent:
    gateway = RobotGateway(SimBackend(sim, store), SafetyPolicy())
    return Agent(gateway, open_endpoint(spec, vision=vision), store, session="test")


def started(sim: Simulator) -> Simulator:
    sim.step(0.5)  # its topics published once at least: the camera's 5 Hz frame too
    return sim


def sent_image(request: dict) -> tuple[str, np.ndarray]:
    """The text part and the image (decoded RGB pixels) of the request's user message."""
    user = request["messages"][-1]
    assert user["role"] == "user" and isinstance(user["content"], list)
    text = next(p["text"] for p in user["content"] if p["type"] == "text")
    url = next(p["image_url"]["url"] for p in user["content"] if p["type"] == "image_url")
    head, _, data = url.partition(",")
    assert head == "data:image/png;base64"
    with Image.open(io.BytesIO(base64.b64decode(data, validate=True))) as img:
        assert img.format == "PNG"
        return text, np.asarray(img.convert("RGB"))


@pytest.mark.parametrize(
    "question",
    ["what is in front of the robot?", "What does the camera see?", "what do you see?",
     "describe the camera image", "what is the robot looking at?"],
)  # fmt: skip
def test_a_question_about_the_view_is_its_own_subject(question):
    intents = intent.classify(question, ["dock"])
    assert subject.subjects_of(question, intents, ["dock"]) == [subject.Subject("view")]


@pytest.mark.parametrize(
    "question",
    ["is there an obstacle in front of the robot?", "what resolution is the camera?",
     "battery level?", "go to the dock"],
)  # fmt: skip
def test_an_obstacle_or_a_camera_setting_is_not_the_view(question):
    found = subject.subjects_of(question, intent.classify(question, ["dock"]), ["dock"])
    assert found is None or subject.Subject("view") not in found


async def test_a_seeing_model_is_sent_the_frame_the_robot_published(llm, store):
    llm.default = SEEN
    sim = started(Simulator(seed=0, start=DOCK_LEFT))
    agent = agent_on(sim, store, f"openai:scripted@{llm.url}", vision=True)
    result = await agent.turn("What is in front of the robot?")
    assert len(llm.requests) == 1
    text, pixels = sent_image(llm.requests[0])
    assert text == "What is in front of the robot?"
    published = agent.gateway.backend.image("/camera/image_raw")
    assert published is not None
    robot = np.frombuffer(published.data, np.uint8).reshape(published.height, published.width, 3)
    _, own = sim.camera_image()  # the simulator's frame: the robot stands still, paused
    assert pixels.shape == (120, 160, 3)
    assert np.array_equal(pixels, robot) and np.array_equal(pixels, own)
    green = [c for c in range(160) if pixels[60, c, 1] > 1.5 * max(pixels[60, c, [0, 2]])]
    assert green and max(green) < 80  # the station on the left of what was sent, not mirrored
    # the answer is the model's, said as coming from that frame, with its age
    assert result.answer.startswith("From the camera frame 0.")
    assert " s old (/camera/image_raw, 160 x 120 px): " + SEEN in result.answer
    age = float(result.answer.removeprefix("From the camera frame ").split(" s old")[0])
    assert 0.0 <= age <= 0.25  # a 5 Hz camera: a frame at most one period old
    read = result.commands[0]
    assert read.command == "ros2 topic echo /camera/image_raw --once" and read.role == "camera"
    assert read.values["png_bytes"] == len(base64.b64decode(sent_url(llm.requests[0])))
    assert read.age_s == pytest.approx(age, abs=0.051)
    row = store.interactions()[0]  # the turn, its read and the model's reply are kept
    assert row["answer"] == result.answer and SEEN in row["raw_replies"]
    assert store.commands_for(row["id"])[0]["command"] == read.command


def sent_url(request: dict) -> str:
    parts = request["messages"][-1]["content"]
    return next(p["image_url"]["url"] for p in parts if p["type"] == "image_url").split(",")[1]


async def test_ollama_is_sent_the_frame_as_its_own_images_field(store):
    server = ScriptedLLM("ollama")
    try:
        server.default = SEEN
        sim = started(Simulator(seed=0, start=DOCK_LEFT))
        agent = agent_on(sim, store, f"ollama:llava@{server.url}", vision=True)
        result = await agent.turn("what does the camera see?")
        user = server.requests[0]["messages"][-1]
        assert user["content"] == "what does the camera see?"
        with Image.open(io.BytesIO(base64.b64decode(user["images"][0]))) as img:
            pixels = np.asarray(img.convert("RGB"))
        assert np.array_equal(pixels, sim.camera_image()[1])
        assert result.answer.endswith(SEEN)
    finally:
        server.close()


async def test_a_model_that_cannot_see_says_so_and_answers_from_the_lidar(llm, store):
    sim = started(Simulator(seed=0, start=DOCK_LEFT))
    for spec, vision in ((f"openai:scripted@{llm.url}", False), ("rules", True)):
        result = await agent_on(sim, store, spec, vision).turn("what is in front of the robot?")
        answer = result.answer.removeprefix("[rules] ")
        assert answer.startswith("This model cannot see images; from the lidar, /scan ("), answer
        nearest = float(re.search(r"straight ahead is (\d+\.\d+) m", answer)[1])
        assert abs(nearest - _nearest_ahead(sim)) < 0.01  # the scan's own, in front
        assert "; /obstacles (" in answer and "no obstacle ahead" in answer
        assert [c.command for c in result.commands] == [
            "ros2 topic echo /scan --once",
            "ros2 topic echo /obstacles --once",
        ]
    assert llm.requests == []  # no model was asked, no view made up


async def test_no_frame_yet_is_said_and_the_lidar_answers(llm, store):
    sim = Simulator(seed=0, camera=None)
    result = await agent_on(sim, store, f"openai:scripted@{llm.url}", True).turn("what do you see?")
    assert result.answer.startswith("No camera frame to look at (no camera); from the lidar")
    assert llm.requests == []


async def test_a_server_that_refuses_the_image_is_said_and_the_lidar_answers(llm, store):
    llm.mode = "http500"
    sim = started(Simulator(seed=0, start=DOCK_LEFT))
    result = await agent_on(sim, store, f"openai:scripted@{llm.url}", True).turn("what's ahead?")
    assert result.answer.startswith("The model could not look at the camera frame (")
    assert "HTTP 500" in result.answer and "; from the lidar, /scan (" in result.answer


def test_vision_marks_the_configured_model_only_and_never_the_embedded_one():
    llm = load_settings({"llm": {"model": "ollama:gemma3", "vision": True}}).llm
    assert llm.marks_vision("ollama:gemma3") and not llm.marks_vision("ollama:other")
    assert open_endpoint("ollama:gemma3", vision=True).sees
    assert not open_endpoint("embedded", vision=True).sees
    assert not open_endpoint("rules", vision=True).sees


def _nearest_ahead(sim) -> float:
    """The simulator's own scan: its nearest return within 30 deg of straight ahead."""
    from astiop.sim import messages as sm

    v = sm.laser_scan(sim.snapshot(), sim.lidar_spec)
    return min(
        r
        for i, r in enumerate(v["ranges"])
        if v["range_min"] <= r <= v["range_max"]
        and abs(math.degrees(v["angle_min"] + i * v["angle_increment"])) <= 30
    )


def test_a_big_frame_is_sent_scaled_down_to_the_models_size_and_a_small_one_whole():
    from astiop.agent.view import MODEL_MAX_SIDE
    from astiop.robot.camera import CameraFrame, fitted, png_of

    assert fitted(160, 120, MODEL_MAX_SIDE) == (160, 120)
    assert fitted(1920, 1080, MODEL_MAX_SIDE) == (896, 504)
    assert fitted(1080, 1920, 896) == (504, 896) and fitted(1920, 1080, None) == (1920, 1080)
    pixels = np.zeros((1080, 1920, 3), dtype=np.uint8)
    pixels[:, 960:] = (0, 200, 0)  # the right half green
    frame = CameraFrame("/camera/image_raw", pixels, "rgb8", 1.0)
    png, _ = png_of(frame, MODEL_MAX_SIDE)
    sent = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    assert sent.shape == (504, 896, 3)
    assert sent[:, :440].max() == 0 and (sent[:, 460:, 1] == 200).all()  # the same picture

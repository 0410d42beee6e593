"""Zones of a map: stored with its places, refused when malformed, enforced by safety on goals
and teleop, obeyed by the simulator's planner and controller, exported as Nav2's masks."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml

from astiop.config import load_settings
from astiop.nav2_masks import read_pgm
from astiop.robot.factory import make_safety
from astiop.robot.gateway import RobotGateway
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.simulator.backend import SimBackend
from astiop.zones import point_in_polygon, polygon_distance
from tests.cli_runner import run_cli

BAY = ["14,7.5", "16,7.5", "16,10", "14,10"]  # across the aisle between the first two racks


def cli(db, *args):
    return run_cli("--db", str(db), "zones", *args)


def one_line(result):
    lines = result.stderr.strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1 and lines[0].startswith("astiop: "), result
    return lines[0]


def test_zones_are_added_listed_shown_renamed_and_removed_on_the_robots_map(tmp_path):
    db = tmp_path / "z.db"
    assert cli(db, "add", "loading_bay", "--keepout", "1,2", "4,2", "4,5", "1,5").returncode == 0
    assert cli(db, "add", "packing", "--speed", "0.3", "10,2", "12,2", "12,5").returncode == 0
    listed = json.loads(cli(db, "list", "--json").stdout)
    assert [(z["name"], z["kind"], z["speed"]) for z in listed] == [
        ("loading_bay", "keepout", None),
        ("packing", "speed", 0.3),
    ]
    assert listed[0]["corners"] == [[1, 2], [4, 2], [4, 5], [1, 5]]
    assert "speed 0.3 m/s" in cli(db, "show", "packing").stdout
    assert cli(db, "rename", "packing", "packing_tables").returncode == 0
    assert cli(db, "remove", "loading_bay").returncode == 0
    assert [z["name"] for z in json.loads(cli(db, "list", "--json").stdout)] == ["packing_tables"]
    # another map's zones are its own
    assert "no zones on the map hall_b" in run_cli("--db", str(db), "zones", "--map", "hall_b",
                                                   "list").stdout  # fmt: skip


@pytest.mark.parametrize(
    "args,why",
    [
        (["--keepout", "1,2", "4,2"], "at least 3 corners"),
        (["--keepout", "1,1", "3,3", "3,1", "1,3"], "crosses itself"),
        (["--keepout", "1,1", "50,1", "3,3"], "outside the map"),
        (["--keepout", "1,x", "2,2", "3,3"], "bad corner '1,x'"),
        (["--speed", "fast", "1,1", "2,1", "2,2"], "bad speed 'fast'"),
        (["--speed", "-1", "1,1", "2,1", "2,2"], "m/s"),
        (["--keepout", "1,1", "2,2", "3,3"], "no area"),
        (["1,1", "2,1", "2,2"], "--keepout or --speed"),
    ],
)
def test_a_bad_zone_gets_one_line_and_stores_nothing(tmp_path, args, why):
    db = tmp_path / "z.db"
    assert why in one_line(cli(db, "add", "bay", *args))
    assert json.loads(cli(db, "list", "--json").stdout) == []


def test_a_duplicate_zone_name_is_refused_whatever_its_case(tmp_path):
    db = tmp_path / "z.db"
    cli(db, "add", "bay", "--keepout", *BAY)
    assert "'bay' already exists" in one_line(
        cli(db, "add", "BAY", "--keepout", "1,1", "2,1", "2,2")
    )
    assert len(json.loads(cli(db, "list", "--json").stdout)) == 1


@pytest.fixture
def gateway(tmp_path):
    store = Store(tmp_path / "g.db")
    sim = Simulator(seed=0, start=(8.0, 8.75, 0.0))
    policy = make_safety(load_settings({}, env={}, path=tmp_path / "n.toml"), store)
    gw = RobotGateway(SimBackend(sim, store), policy, store=store)
    yield gw
    gw.close()
    store.close()


def _run(gw, text):
    return gw.run(text, confirm=lambda c: True)


def test_a_goal_into_a_keepout_zone_is_refused_naming_it_on_every_way_of_sending_one(gateway):
    store = gateway.store
    store.add_zone("loading_bay", "keepout", [(14, 7.5), (16, 7.5), (16, 10), (14, 10)])
    store.add_location("bay_door", 15.0, 8.75)
    sim = gateway.backend.sim
    for text in (
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{x: 15.0, y: 8.5}"',
        'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{name: bay_door}"',
        "ros2 action send_goal /navigate_to_pose nav2_msgs/action/NavigateToPose "
        '"{pose: {header: {frame_id: map}, pose: {position: {x: 15.5, y: 9.0}, '
        'orientation: {w: 1.0}}}}"',
    ):
        r = _run(gateway, text)
        assert not r.executed and "keepout zone 'loading_bay'" in r.reason, r.reason
        assert "\n" not in r.reason and sim.goal is None
    # beside it, a goal goes
    r = _run(
        gateway, 'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{x: 12, y: 8.75}"'
    )
    assert r.executed and sim.goal is not None


def test_teleop_is_refused_into_a_keepout_zone_and_slowed_in_a_speed_zone(gateway):
    store, sim = gateway.store, gateway.backend.sim
    store.add_zone("bay", "keepout", [(8.6, 7.6), (9.6, 7.6), (9.6, 9.9), (8.6, 9.9)])
    ahead = gateway.drive(0.5, 0.0, 0.0)  # facing +x, the zone 0.6 m ahead
    assert not ahead.executed and "keepout zone 'bay'" in ahead.reason
    assert gateway.drive(0.0, 0.0, 0.5).executed  # turning on the spot stays allowed
    assert gateway.drive(-0.5, 0.0, 0.0).executed  # and backing away
    store.remove_zone("bay")
    store.add_zone("tables", "speed", [(6, 7.6), (11, 7.6), (11, 9.9), (6, 9.9)], 0.2)
    fast = gateway.drive(0.6, 0.0, 0.0)
    assert fast.executed and math.isclose(fast.values["linear"]["x"], 0.2, abs_tol=1e-9)
    assert any("speed zone 'tables'" in n for n in fast.notes), fast.notes
    assert sim is gateway.backend.sim


def test_the_simulators_robot_takes_the_other_way_round_a_keepout_zone(gateway):
    store, sim = gateway.store, gateway.backend.sim
    store.add_zone("aisle_block", "keepout", [(14, 7.5), (16, 7.5), (16, 10), (14, 10)])
    corners = store.require_zone("aisle_block").corners
    r = _run(
        gateway, 'ros2 service call /goto_position astiop_msgs/srv/GotoPosition "{x: 32, y: 8.75}"'
    )
    assert r.executed, r.reason
    closest = math.inf
    while sim.goal is not None and sim.t < 240:
        sim.step(0.1)
        closest = min(closest, polygon_distance(*sim.pose[:2], corners))
    assert sim.last_result.status == "succeeded", sim.last_result
    assert closest > sim.chassis.width / 2  # not even the body's side went in


def test_the_simulator_refuses_a_goal_with_no_way_round_and_one_inside(gateway):
    sim = gateway.backend.sim
    wall = [(11, 0.3), (12, 0.3), (12, 24.7), (11, 24.7)]  # the whole warehouse cut in two
    sim.set_zones([gateway.store.add_zone("cut", "keepout", wall)])
    with pytest.raises(ValueError, match="no path"):
        sim.goto(32, 8.75, 0.0)
    with pytest.raises(ValueError, match="keepout zone 'cut'"):
        sim.goto(11.5, 8.75, 0.0)


def test_the_simulators_base_keeps_to_a_speed_zones_limit(gateway):
    store, sim = gateway.store, gateway.backend.sim
    store.add_zone("slow", "speed", [(14, 7.6), (20, 7.6), (20, 9.9), (14, 9.9)], 0.25)
    corners = store.require_zone("slow").corners
    sim.goto(30, 8.75, 0.0)
    inside, outside = [], []
    while sim.goal is not None and sim.t < 240:
        sim.step(0.05)
        (inside if point_in_polygon(*sim.pose[:2], corners) else outside).append(sim.speed())
    assert sim.last_result.status == "succeeded"
    assert inside and max(inside) <= 0.25 + 0.02, max(inside)
    assert max(outside) > 0.5  # outside it the robot drives at its own speed


def test_exported_nav2_masks_have_the_zones_pixels(tmp_path):
    db, out = tmp_path / "z.db", tmp_path / "nav2"
    cli(db, "add", "loading_bay", "--keepout", "1,2", "4,2", "4,5", "1,5")
    cli(db, "add", "ramp", "--speed", "0.3", "10,10", "16,10", "10,16")
    done = cli(db, "export", "--nav2", str(out))
    assert done.returncode == 0, done.stderr
    keepout_meta = yaml.safe_load((out / "keepout_mask.yaml").read_text())
    assert keepout_meta["mode"] == "raw" and keepout_meta["origin"] == [0.0, 0.0, 0.0]
    res = keepout_meta["resolution"]
    keepout = read_pgm(out / keepout_meta["image"])
    assert keepout.shape == (500, 800)  # 25 m x 40 m at 0.05 m
    # row 0 is the top (y = 25 m): y 2..5 m are rows 400..459, x 1..4 m columns 20..79
    expected = np.zeros_like(keepout)
    expected[400:460, 20:80] = 100
    assert (keepout == expected).all()
    speed = read_pgm(out / "speed_mask.pgm")
    params = yaml.safe_load((out / "costmap_filter_info.yaml").read_text())
    info = params["speed_filter_info_server"]["ros__parameters"]
    assert (
        info["type"] == 2 and params["keepout_filter_info_server"]["ros__parameters"]["type"] == 0
    )
    values = set(np.unique(speed)) - {0}
    assert len(values) == 1
    limit = info["base"] + info["multiplier"] * values.pop()
    assert math.isclose(limit, 0.3, abs_tol=1e-9)
    rows, cols = np.nonzero(speed)
    xs, ys = (cols + 0.5) * res, 25 - (rows + 0.5) * res
    assert all(point_in_polygon(x, y, [(10, 10), (16, 10), (10, 16)]) for x, y in zip(xs, ys))
    assert math.isclose(len(xs) * res * res, 18.0, rel_tol=0.02)  # the triangle's 18 m²
    server = params["speed_mask_server"]["ros__parameters"]
    assert server["topic_name"] == info["mask_topic"] and server["yaml_filename"].endswith(
        "speed_mask.yaml"
    )


def test_asked_in_chat_a_place_inside_a_keepout_zone_is_answered_with_the_zone(tmp_path):
    db = tmp_path / "z.db"
    cli(db, "add", "ship_block", "--keepout", "36,2", "39,2", "39,6", "36,6")
    r = run_cli("--db", str(db), "--model", "rules", "chat", "can the robot go to shipping?")
    assert "NOT RUN" in r.stdout + r.stderr and "keepout zone 'ship_block'" in r.stdout + r.stderr

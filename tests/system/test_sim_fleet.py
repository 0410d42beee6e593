"""Several ASTIbots in one warehouse, as an operator would notice them: each on its own dock and
battery, each seen by the others' lidars, none passing through another, and two sent face to
face through one aisle both getting there."""

import math

import pytest

from astiop.sim.fleet import SimFleet, dock_name, with_docks
from astiop.sim.navigation import ROBOT_GIVE_UP_S
from astiop.warehouse import default_map

AISLE_Y = 8.75  # between the shelf rows at y 6.5-7.5 and 10-11


def _run(fleet: SimFleet, seconds: float, watch=None) -> float:
    """Step the fleet until no robot has a goal (or `seconds`); the closest two robots' centres
    came, and `watch()` after every step."""
    closest = math.inf
    end = fleet.t + seconds
    while fleet.t < end and any(r.goal is not None for r in fleet.robots):
        fleet.step(0.1)
        for i, a in enumerate(fleet.robots):
            for b in fleet.robots[i + 1 :]:
                closest = min(closest, math.dist(a.pose[:2], b.pose[:2]))
        if watch:
            watch()
    return closest


def test_each_robot_starts_on_its_own_dock_charging_and_drains_its_own_battery():
    fleet = SimFleet(["a", "b", "c"])
    fleet.step(0.2)
    docks = [fleet.map.station(dock_name(i)) for i in range(3)]
    assert len({d.docked_pose for d in docks}) == 3
    for robot, dock in zip(fleet.robots, docks, strict=True):
        assert robot.pose == pytest.approx(dock.docked_pose)
        assert robot.docked() and robot.state_word() == "charging"
    b = fleet.robots[1]
    b.undock()
    _run(fleet, 60)
    b.goto(20.0, AISLE_Y + 3.5, 0.0)
    _run(fleet, 120)
    assert b.last_result.status == "succeeded"
    a, c = fleet.robots[0], fleet.robots[2]
    assert a.battery.soc == pytest.approx(c.battery.soc) and b.battery.soc < a.battery.soc - 0.001
    b.dock()  # back between its neighbours, still docked on theirs
    _run(fleet, 200)
    assert b.last_result.status == "succeeded" and b.docked(), b.events_since(0)[-3:]
    assert a.docked() and c.docked()


def test_a_robot_sees_another_on_its_lidar_as_a_robot():
    fleet = SimFleet(["a", "b"], starts=[(12.0, AISLE_Y, 0.0), (16.0, AISLE_Y, math.pi)])
    fleet.step(0.2)
    a = fleet.robots[0]
    seen = [o for o in a.detected if o.kind == "robot"]
    assert seen and seen[0].robot == 1
    assert seen[0].distance == pytest.approx(4.0 - 0.5, abs=0.05)  # to b's front face
    assert abs(seen[0].bearing) < math.radians(5)


def test_two_robots_face_to_face_in_one_aisle_both_arrive_and_never_touch():
    fleet = SimFleet(["a", "b"], starts=[(12.0, AISLE_Y, 0.0), (18.0, AISLE_Y, math.pi)])
    a, b = fleet.robots
    a.goto(18.5, AISLE_Y, 0.0)
    b.goto(11.5, AISLE_Y, math.pi)
    closest = _run(fleet, 300)
    assert a.last_result.status == "succeeded" and b.last_result.status == "succeeded"
    assert closest > a.chassis.length + 0.5  # centres never closer than a body and a margin
    assert a.collisions == b.collisions == 0 and a.max_penetration == 0.0
    said = [e.message for e in b.events_since(0)]
    assert any("planned around a robot" in m for m in said), said  # the later robot gave way
    assert not any("planned around" in e.message for e in a.events_since(0))


def test_a_robot_in_the_way_with_no_way_around_is_waited_for_then_reported():
    # b stands idle at a's goal: a waits, then gives the goal up and says why
    fleet = SimFleet(["a", "b"], starts=[(12.0, AISLE_Y, 0.0), (16.0, AISLE_Y, math.pi)])
    a, b = fleet.robots
    a.goto(16.0, AISLE_Y, 0.0)
    _run(fleet, ROBOT_GIVE_UP_S + 20)
    assert a.last_result.status == "aborted"
    assert "another robot stayed in the way" in a.last_result.message
    assert a.collisions == b.collisions == 0
    assert math.dist(a.pose[:2], b.pose[:2]) > a.chassis.length


def test_an_idle_robot_in_an_open_aisle_is_planned_around():
    fleet = SimFleet(["a", "b"], starts=[(3.0, 12.0, -math.pi / 2), (3.0, 8.0, 0.0)])
    a, b = fleet.robots
    a.goto(3.0, 4.5, -math.pi / 2)  # straight through b, along the open west side
    closest = _run(fleet, 120)
    assert a.last_result.status == "succeeded", a.last_result
    assert closest > a.chassis.width and a.collisions == b.collisions == 0
    assert b.pose == pytest.approx((3.0, 8.0, 0.0), abs=1e-3)  # never pushed


def test_driven_into_another_robot_is_a_collision_never_a_pass_through():
    fleet = SimFleet(["a", "b"], starts=[(12.0, AISLE_Y, 0.0), (14.0, AISLE_Y, 0.0)])
    a, b = fleet.robots
    while not a.fault and fleet.t < 10:  # teleop does not yield: the operator drives it into b
        a.set_cmd_vel(0.5, 0.0, 0.0)
        fleet.step(0.1)
    fleet.step(1.0)
    assert a.fault == "collision with robot b"
    assert a.pose[0] < b.pose[0] - a.chassis.length + 0.02  # touching, not overlapping
    assert b.collisions == 0  # b stood still: the fault is the one that moved


def test_a_fleet_robot_is_stepped_by_its_fleet_only():
    fleet = SimFleet(["a", "b"])
    with pytest.raises(RuntimeError, match="stepped by its fleet"):
        fleet.robots[0].step(0.1)


def test_docks_fit_fifty_robots_and_say_when_more_do_not_fit():
    docks = [s for s in with_docks(default_map(), 50).stations if s.kind == "dock"]
    assert len(docks) == 50 and len({s.docked_pose for s in docks}) == 50
    with pytest.raises(ValueError, match="do not fit"):
        with_docks(default_map(), 80)

"""The simulator's helpers, each built alone from the pieces it is handed (no `Simulator`): the
holds, the clock's event log, the base, the scanner, navigation, the commands and the physics
step."""

import math
import threading
from types import SimpleNamespace

import numpy as np
import pytest

from astiop.sim.base import A_LIN, Base, Teleop
from astiop.sim.battery import Battery
from astiop.sim.body import ASTIBOT_BODY
from astiop.sim.clock import Clock, SimEvents
from astiop.sim.commands import SimCommands
from astiop.sim.controller import ControllerGains
from astiop.sim.conveyor import Conveyor
from astiop.sim.goal import GoalError
from astiop.sim.holds import Holds
from astiop.sim.kinematics import ASTIBOT
from astiop.sim.lidar import LidarSpec
from astiop.sim.navigation import Navigation
from astiop.sim.path_planner import PathPlanner
from astiop.sim.scanner import Scanner
from astiop.sim.stepping import Physics
from astiop.sim.world import World
from astiop.warehouse import default_map, parse_map
from astiop.zones import MapZone

ROOM = parse_map(
    {
        "name": "room",
        "bounds": [0, 0, 10, 10],
        "walls": [[0, 0, 10, 0.5], [0, 9.5, 10, 10], [0, 0.5, 0.5, 9.5], [9.5, 0.5, 10, 9.5]],
    }
)
DT = 0.01


def _parts(warehouse=ROOM, start=(5.0, 5.0, 0.0), seed=0, dock="charging_dock"):
    """Navigation and what it is handed, wired by hand."""
    lock = threading.RLock()
    clock = Clock(DT)
    events = SimEvents(clock)
    world = World(warehouse)
    base = Base(world, start, ASTIBOT_BODY, ASTIBOT, owner=None)
    holds = Holds()
    scanner = Scanner(world, base, clock, LidarSpec(), np.random.default_rng(seed))
    planner = PathPlanner(world.static_boxes, warehouse.bounds, ASTIBOT_BODY.inflation)
    navigation = Navigation(
        lock=lock, warehouse=warehouse, dock_name=dock, world=world, planner=planner, base=base,
        holds=holds, scanner=scanner, clock=clock, events=events, gains=ControllerGains(),
        blocked_give_up_s=5.0,
    )  # fmt: skip
    return SimpleNamespace(
        lock=lock, clock=clock, events=events, world=world, base=base, holds=holds,
        scanner=scanner, navigation=navigation, conveyor=Conveyor(),
    )  # fmt: skip


def _commands(p) -> SimCommands:
    return SimCommands(
        lock=p.lock, clock=p.clock, events=p.events, holds=p.holds, base=p.base,
        navigation=p.navigation, conveyor=p.conveyor, world=p.world,
    )  # fmt: skip


def _physics(p, in_fleet=False) -> Physics:
    return Physics(
        lock=p.lock, clock=p.clock, world=p.world, base=p.base, holds=p.holds,
        navigation=p.navigation, scanner=p.scanner, battery=Battery(0.5), conveyor=p.conveyor,
        events=p.events, physics_hz=round(1 / DT), in_fleet=in_fleet,
    )  # fmt: skip


def test_holds_refuse_motion_saying_why_and_hold_until_released():
    holds = Holds()
    holds.check_can_move()
    assert not holds.held
    holds.fault = "collision with wall"
    assert not holds.held  # a fault refuses motion, /stop acknowledges it: no hold
    with pytest.raises(GoalError, match=r"fault \(collision with wall\)"):
        holds.check_can_move()
    holds.stop_latched = True
    assert holds.held
    with pytest.raises(GoalError, match="latched"):
        holds.check_can_move()
    holds.e_stopped = True
    with pytest.raises(GoalError, match="e-stopped"):
        holds.check_can_move()


def test_events_are_numbered_stamped_with_the_clock_and_the_last_500_kept():
    clock = Clock(DT)
    events = SimEvents(clock)
    events.say("goal", "accepted")
    clock.t = 1.5
    events.say("fault", "collision", "error")
    first, second = events.since(0)
    assert (first.seq, first.t, first.kind, first.severity) == (1, 0.0, "goal", "info")
    assert (second.seq, second.t, second.severity) == (2, 1.5, "error")
    assert events.since(1) == [second] and events.since(2) == []
    for i in range(600):
        events.say("world", f"event {i}")
    kept = events.since(0)
    assert len(kept) == 500 and kept[0].seq == 103 and kept[-1].seq == events.seq == 602


def test_the_base_ramps_toward_its_target_and_halts_at_once():
    world = World(ROOM)
    base = Base(world, (5.0, 5.0, math.pi / 2), ASTIBOT_BODY, ASTIBOT, owner=None)
    assert base.pose == (5.0, 5.0, math.pi / 2) and base.speed() == 0.0
    base.target = (0.5, 0.0, 0.0)
    for _ in range(10):
        base.ramp(DT, halted=False)
        world.step(DT)
    assert base.v[0] == pytest.approx(10 * A_LIN * DT) and base.v[1:] == [0.0, 0.0]
    vx, vy = base.control.velocity  # facing +y: the robot's forward is the map's +y
    assert vx == pytest.approx(0.0, abs=1e-12) and vy == pytest.approx(0.1)
    for _ in range(100):
        base.ramp(DT, halted=False)
        world.step(DT)
    assert base.v == [0.5, 0.0, 0.0] and base.speed() == 0.5  # reached, never beyond
    assert base.pose[1] > 5.3 and base.pose[0] == pytest.approx(5.0, abs=1e-3)
    base.ramp(DT, halted=True)
    assert base.v == [0.0, 0.0, 0.0]
    base.v[:] = (0.3, 0.0, 0.1)
    base.teleop = Teleop((0.3, 0.0, 0.1), until=9.0)
    base.halt()
    assert base.v == [0.0, 0.0, 0.0] and base.teleop == Teleop() and base.applied == (0, 0, 0)
    assert tuple(base.control.velocity) == (0, 0) and base.control.angular_velocity == 0.0


def test_the_scanner_sees_a_square_room_and_finds_a_person_in_it():
    world, clock = World(ROOM), Clock(DT)
    base = Base(world, (5.0, 5.0, 0.3), ASTIBOT_BODY, ASTIBOT, owner=None)
    scanner = Scanner(world, base, clock, LidarSpec(), np.random.default_rng(3))
    scanner.scan()
    angles = LidarSpec().beam_angles() + 0.3
    expected = 4.5 / np.maximum(np.abs(np.cos(angles)), np.abs(np.sin(angles)))
    assert np.all(np.abs(scanner.ranges - expected) < 0.05) and scanner.detected == []
    world.add_obstacle("person", 8.0, 5.5)
    clock.t = 2.0
    scanner.scan()
    (person,) = scanner.detected
    assert person.kind == "person" and scanner.stamp == 2.0 and len(scanner.ms) == 2
    assert person.distance == pytest.approx(math.hypot(3.0, 0.5) - 0.3, abs=0.1)


def test_navigation_plans_drives_and_ends_a_goal_on_its_own():
    p = _parts()
    nav = p.navigation
    p.base.teleop = Teleop((0.2, 0.0, 0.0), until=5.0)
    goal = nav.goto(8.0, 5.0, 0.0, "east")
    assert nav.goal is goal and nav.plan[0] == (5.0, 5.0) and nav.plan[-1] == (8.0, 5.0)
    assert p.base.teleop == Teleop()  # a goal ends teleop
    assert [e.message for e in p.events.since(0)] == ["goal 1 accepted: east"]
    vx, vy, wz = nav.navigate(goal)
    assert vx > 0.0 and abs(vy) < 1e-9 and abs(wz) < 1e-9  # straight ahead, +x
    p.base.target = (vx, vy, wz)
    assert nav.cancel("canceled by the test") and nav.goal is None and nav.plan == ()
    assert nav.last_result.status == "canceled" and nav.last_result.error_m == 3.0
    assert p.base.target == (0.0, 0.0, 0.0)
    p.holds.e_stopped = True
    with pytest.raises(GoalError, match="e-stopped"):
        nav.goto(8.0, 5.0, 0.0)
    assert nav.goal is None and len(p.events.since(0)) == 2


def test_navigation_refuses_goals_the_base_cannot_stand_at_and_keeps_to_zones():
    p = _parts()
    nav = p.navigation
    for goal, why in [
        ((math.nan, 1.0, 0.0), "finite"),
        ((12.0, 5.0, 0.0), "outside the map"),
        ((0.6, 5.0, 0.0), "does not fit"),
    ]:
        with pytest.raises(GoalError, match=why):
            nav.check_goal(*goal)
    corners = ((6.0, 4.0), (7.0, 4.0), (7.0, 6.0), (6.0, 6.0))
    slow = ((4.0, 3.0), (9.0, 3.0), (9.0, 7.0), (4.0, 7.0))
    nav.set_zones([MapZone("pit", "keepout", corners), MapZone("slow", "speed", slow, 0.2)])
    with pytest.raises(GoalError, match="inside the keepout zone 'pit'"):
        nav.check_goal(6.5, 5.0, 0.0)
    assert nav.zone_speed((0.8, 0.0, 0.1)) == pytest.approx((0.2, 0.0, 0.1))
    assert nav.zone_speed((0.1, 0.0, 0.1)) == (0.1, 0.0, 0.1)


def test_navigation_knows_when_the_base_stands_docked():
    warehouse = default_map()
    docked = warehouse.station("charging_dock").docked_pose
    p = _parts(warehouse, start=docked)
    assert p.navigation.docked()
    with pytest.raises(GoalError, match="already docked"):
        p.navigation.dock()
    p.base.v[:] = (0.2, 0.0, 0.0)  # moving through it is not docked
    assert not p.navigation.docked()
    assert not _parts(ROOM).navigation.docked()  # a map with no dock


def test_commands_latch_a_stop_say_an_ignored_teleop_once_and_release():
    p = _parts()
    commands = _commands(p)
    p.navigation.goto(8.0, 5.0, 0.0)
    assert commands.stop() == "stopped; goal canceled" and p.holds.stop_latched
    commands.set_cmd_vel(0.0, 0.0, 0.0)  # a zero Twist agrees with the hold
    for _ in range(2):
        with pytest.raises(GoalError, match="latched"):
            commands.set_cmd_vel(0.3, 0.0, 0.0)
    said = [e.message for e in p.events.since(0)]
    assert sum("/cmd_vel ignored" in m for m in said) == 1
    assert commands.release() == "released: the robot may move again"
    assert commands.release() == "released; nothing was held"
    p.clock.t = 2.0
    commands.set_cmd_vel(0.3, 0.0, 0.1)
    assert p.base.teleop == Teleop((0.3, 0.0, 0.1), 2.5)
    with pytest.raises(GoalError, match="not at a conveyor station"):
        commands.conveyor_transfer(1)


def test_commands_estop_halts_the_base_cancels_the_goal_and_stops_the_conveyor():
    p = _parts()
    commands = _commands(p)
    p.navigation.goto(8.0, 5.0, 0.0)
    p.conveyor.start(1)
    p.base.v[:] = (0.4, 0.0, 0.0)
    commands.estop()
    assert p.holds.e_stopped and p.navigation.goal is None and not p.conveyor.running
    assert p.base.v == [0.0, 0.0, 0.0] and tuple(p.base.control.velocity) == (0, 0)
    assert p.navigation.last_result.message == "e-stop"
    assert [e.message for e in p.events.since(1)] == ["goal 1 canceled: e-stop", "E-STOP engaged"]


def test_physics_steps_whole_substeps_and_carries_the_rest():
    p = _parts()
    physics = _physics(p)
    stepped = []
    physics.after_step.append(lambda: stepped.append(p.clock.tick))
    physics.step(0.105)
    assert p.clock.tick == 10 and p.clock.t == pytest.approx(0.1)
    physics.step(0.005)  # the carried 5 ms and these make one more substep
    assert p.clock.tick == 11 and stepped == [10, 11]
    assert p.scanner.stamp == pytest.approx(0.1)  # the lidar's 10 Hz
    with pytest.raises(RuntimeError, match="stepped by its fleet"):
        _physics(_parts(), in_fleet=True).step(0.1)


def test_physics_drives_teleop_drains_the_battery_and_faults_on_a_wall():
    p = _parts(start=(7.5, 5.0, 0.0))
    physics = _physics(p)
    p.base.teleop = Teleop((0.5, 0.0, 0.0), until=100.0)
    physics.step(1.0)
    assert p.base.v[0] == pytest.approx(0.5) and p.base.pose[0] > 7.7
    assert physics.battery.soc < 0.5 and physics.motor_power > 0.0
    physics.run_until(lambda: p.holds.fault != "", 10.0)
    assert p.holds.fault == "collision with wall" and physics.collisions == 1
    assert p.base.v == [0.0, 0.0, 0.0] and p.base.teleop == Teleop()
    assert p.base.pose[0] + ASTIBOT_BODY.length / 2 < 9.5 + 0.01  # stopped at the wall
    assert physics.max_penetration < 0.01
    assert p.events.since(0)[-1].message.startswith("collision with wall at (")


def test_the_simulators_attributes_are_its_helpers_state_read_and_written_through():
    from astiop.sim.simulator import Simulator

    sim = Simulator(ROOM, start=(5.0, 5.0, 0.0), lidar_enabled=False)
    sim.gains = ControllerGains(v_max=0.3)  # as the ROS node's max_vel parameter does
    sim.e_stopped = True
    sim.zone_source = list
    assert sim.navigation.gains.v_max == 0.3 and sim.holds.e_stopped and sim.held
    assert sim.navigation.zone_source is list
    with pytest.raises(GoalError, match="e-stopped"):
        sim.goto(8.0, 5.0, 0.0)
    sim.release()
    goal = sim.goto(8.0, 5.0, 0.0)
    assert sim.goal is goal is sim.navigation.goal and sim.plan == sim.navigation.plan
    sim.step(0.5)
    assert sim.t == sim.clock.t == pytest.approx(0.5) and sim.pose == sim.base.pose
    assert sim.scan_ranges is sim.scanner.ranges and sim.after_step is sim.physics.after_step
    assert sim.snapshot().vx == sim.base.v[0] > 0.0

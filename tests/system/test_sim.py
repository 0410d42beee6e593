"""The simulator as an operator would notice it: it gets there, it stops, it senses, it drains."""

import math

import numpy as np
import pytest

from astiop.sim.controller import tracking_error
from astiop.sim.lidar import LidarSpec, cast
from astiop.sim.path_planner import PathPlanner, PlanningError
from astiop.sim.simulator import ROBOT_LENGTH, GoalError, Simulator
from astiop.warehouse import parse_map

ROOM = parse_map(
    {
        "name": "room",
        "bounds": [0, 0, 10, 10],
        "walls": [[0, 0, 10, 0.5], [0, 9.5, 10, 10], [0, 0.5, 0.5, 9.5], [9.5, 0.5, 10, 9.5]],
    }
)


def test_tracking_error_is_eq_8():
    # goal 1 m ahead-left of a robot facing +y: in the robot frame it is ahead (x) and right (-y)
    ex, ey, eth = tracking_error((2.0, 3.0, math.pi / 2), (3.0, 4.0, math.pi))
    assert ex == pytest.approx(1.0) and ey == pytest.approx(-1.0)
    assert eth == pytest.approx(math.pi / 2)


def test_goto_converges_from_many_seeded_starts():
    rng = np.random.default_rng(7)
    sim0 = Simulator(seed=0, lidar_enabled=False)
    goal = (20.0, 12.25, math.radians(-90))
    done = 0
    while done < 8:
        x, y = rng.uniform(1.5, 38.5), rng.uniform(1.5, 23.5)
        th = rng.uniform(-math.pi, math.pi)
        try:
            sim0.check_goal(x, y, th)
        except GoalError:
            continue
        sim = Simulator(seed=done, start=(x, y, th), lidar_enabled=False)
        sim.goto(*goal, name="centre")
        result = sim.run_goal(300)
        assert result.status == "succeeded", (x, y, result)
        ex, ey, eth = tracking_error(sim.pose, goal)
        assert math.hypot(ex, ey) < 0.05 and abs(eth) < math.radians(3)
        assert sim.collisions == 0
        done += 1


def test_holonomic_sideways_motion_keeps_heading():
    sim = Simulator(start=(5.0, 12.0, 0.0), lidar_enabled=False)
    sim.goto(5.0, 14.0, 0.0)
    sim.run_goal(60)
    x, y, th = sim.pose
    assert abs(th) < math.radians(2) and abs(y - 14.0) < 0.05


def test_collision_stops_the_robot_and_raises_a_fault():
    # facing a shelf (y = 6.5 .. 7.5) from the south, driven at the motor limit
    sim = Simulator(start=(15.0, 5.0, math.pi / 2), lidar_enabled=False)
    for _ in range(40):
        if sim.fault:
            break
        sim.set_cmd_vel(1.4, 0.0, 0.0)
        sim.step(0.1)
    assert sim.fault.startswith("collision with shelf")
    sim.step(1.0)
    state = sim.snapshot()
    assert state.state == "fault" and state.speed == 0.0
    assert sim.max_penetration < 0.01
    assert sim.pose[1] + ROBOT_LENGTH / 2 < 6.5 + 0.01
    with pytest.raises(GoalError, match="fault"):
        sim.goto(2.5, 3.0, 0.0)
    sim.stop()  # acknowledges the fault, and holds the base until /release
    assert not sim.fault and sim.snapshot().state == "e_stopped"
    sim.release()
    assert sim.snapshot().state == "idle"


def test_lidar_matches_an_analytic_square_room():
    sim = Simulator(ROOM, start=(5.0, 5.0, 0.3), seed=3)
    state = sim.snapshot()
    angles = LidarSpec().beam_angles() + 0.3
    expected = 4.5 / np.maximum(np.abs(np.cos(angles)), np.abs(np.sin(angles)))
    err = state.scan_ranges - expected
    assert np.all(np.abs(err) < 0.05)  # 5 sigma of the 1 cm noise
    assert 0.007 < err.std() < 0.013


def test_lidar_exact_without_noise_and_range_limit():
    a = np.array([[3.0, -1.0]])
    b = np.array([[3.0, 1.0]])
    ranges, hit = cast(0, 0, 0, b, a, LidarSpec())  # edge faces the origin (b -> a downward)
    assert ranges[180] == pytest.approx(3.0, abs=1e-12) and hit[180] == 0
    assert np.isinf(ranges[0])
    far, _ = cast(0, 0, 0, b + [30, 0], a + [30, 0], LidarSpec())
    assert np.all(np.isinf(far))


def test_obstacle_detector_finds_a_person_ahead():
    sim = Simulator(start=(5.0, 12.0, 0.0), seed=1)
    sim.add_obstacle("person", 8.0, 12.5)
    sim.step(0.2)
    found = sim.snapshot().detected
    assert len(found) == 1
    ob = found[0]
    assert ob.kind == "person"
    assert ob.distance == pytest.approx(math.hypot(3.0, 0.5) - 0.3, abs=0.1)
    assert abs(ob.bearing - math.atan2(0.5, 3.0)) < 0.1


def test_replans_around_an_obstacle_in_the_aisle():
    sim = Simulator(start=(8.0, 8.75, 0.0), seed=2)
    sim.add_obstacle("pallet", 16.0, 8.75)
    sim.goto(28.0, 8.75, 0.0, "east end")
    result = sim.run_goal(300)
    assert result.status == "succeeded"
    assert sim.collisions == 0


def test_blocked_when_no_way_round_and_abort():
    sim = Simulator(ROOM, start=(2.0, 5.0, 0.0), seed=2, blocked_give_up_s=5.0)
    sim.add_obstacle("forklift", 5.0, 3.0, math.pi / 2)
    sim.add_obstacle("forklift", 5.0, 7.0, math.pi / 2)
    sim.add_obstacle("pallet", 5.0, 5.0, math.pi / 2)
    sim.goto(8.0, 5.0, 0.0)
    sim.run_until(lambda: sim.snapshot().state == "blocked", 30)
    assert sim.snapshot().state == "blocked" and sim.collisions == 0
    result = sim.run_goal(120)
    assert result.status == "aborted" and result.message == "path blocked for 5 s"


def test_estop_during_navigation_wins():
    sim = Simulator(seed=0)
    sim.goto(8.0, 22.6, math.pi / 2, "assembly_station")
    sim.step(5.0)
    sim.estop()
    pose = sim.pose
    sim.step(3.0)
    state = sim.snapshot()
    assert state.state == "e_stopped" and state.active_goal == ""
    assert math.dist(pose[:2], sim.pose[:2]) < 0.02
    with pytest.raises(GoalError, match="e-stop"):
        sim.goto(8.0, 22.6, 0.0)
    with pytest.raises(GoalError):
        sim.set_cmd_vel(0.5, 0, 0)
    sim.release_estop()
    sim.goto(8.0, 22.6, math.pi / 2)
    assert sim.run_goal(200).status == "succeeded"


def _events(sim, words: str) -> list[str]:
    return [e.message for e in sim.events_since(0) if words in e.message]


def test_stop_latches_the_base_until_release():
    sim = Simulator(start="assembly_station", seed=0, lidar_enabled=False)
    sim.set_cmd_vel(0.0, 0.4, 0.0, timeout=2.0)
    sim.step(1.0)
    assert sim.speed() > 0.3
    assert sim.stop() == "stopped"
    sim.step(1.5)  # a controlled stop: the base ramps down at its deceleration
    rest = sim.pose
    for _ in range(20):  # /cmd_vel at 10 Hz for 2 s: refused, the base stays at rest
        with pytest.raises(GoalError, match="latched"):
            sim.set_cmd_vel(0.0, 0.4, 0.0)
        sim.set_cmd_vel(0.0, 0.0, 0.0)  # a zero Twist agrees with the hold: no complaint
        sim.step(0.1)
        assert sim.speed() == 0.0
    assert math.dist(rest[:2], sim.pose[:2]) < 1e-6
    for job in (lambda: sim.goto(20.0, 12.25, 0.0), sim.dock, lambda: sim.conveyor_transfer(1)):
        with pytest.raises(GoalError, match="latched"):
            job()
    state = sim.snapshot()
    assert state.state == "e_stopped" and state.lamp == "red" and state.active_goal == ""
    assert state.stop_latched and not state.e_stopped  # held by /stop, not by the E-STOP input
    assert _events(sim, "stop latched") == ["stop latched: /release to move again"]
    assert len(_events(sim, "/cmd_vel ignored")) == 1, "said once per hold, not per Twist"
    sim.stop()  # a second /stop while held: still one hold
    assert len(_events(sim, "stop latched")) == 1
    assert sim.release() == "released: the robot may move again"
    assert sim.snapshot().state == "idle" and not sim.snapshot().stop_latched
    sim.set_cmd_vel(0.0, 0.4, 0.0, timeout=2.0)
    sim.step(1.0)
    assert sim.speed() > 0.3 and math.dist(rest[:2], sim.pose[:2]) > 0.1
    assert not sim.fault
    sim.stop()  # the next hold says so again
    with pytest.raises(GoalError, match="latched"):
        sim.set_cmd_vel(0.0, 0.4, 0.0)
    assert len(_events(sim, "stop latched")) == 2 and len(_events(sim, "/cmd_vel ignored")) == 2


def test_a_stopped_goal_stays_stopped_and_release_ends_the_estop_too():
    sim = Simulator(seed=0, lidar_enabled=False)
    sim.goto(8.0, 22.6, math.pi / 2, "assembly_station")
    sim.step(5.0)
    assert sim.stop() == "stopped; goal canceled"
    sim.step(2.0)
    rest = sim.pose
    sim.step(3.0)
    assert sim.goal is None and math.dist(rest[:2], sim.pose[:2]) < 1e-6
    sim.estop()  # the E-STOP input on top of the latched stop: one release ends both
    assert sim.snapshot().e_stopped and sim.snapshot().stop_latched
    assert sim.release() == "released: the robot may move again"
    assert not sim.held and sim.release() == "released; nothing was held"
    sim.goto(8.0, 22.6, math.pi / 2)
    assert sim.run_goal(200).status == "succeeded"


@pytest.mark.parametrize(
    "goal,reason",
    [
        ((15.0, 7.0, 0.0), "shelf"),
        ((45.0, 3.0, 0.0), "outside"),
        ((0.1, 12.0, 0.0), "wall"),
    ],
)
def test_impossible_goals_are_refused_and_change_nothing(goal, reason):
    sim = Simulator(seed=0)
    before = sim.snapshot()
    with pytest.raises(GoalError, match=reason):
        sim.goto(*goal)
    after = sim.snapshot()
    assert after.active_goal == "" and (after.x, after.y) == (before.x, before.y)


def test_battery_drains_driving_and_charges_docked():
    sim = Simulator(seed=0, battery_soc=0.5, lidar_enabled=False)
    sim.step(60)
    assert sim.snapshot().state == "charging"
    assert sim.battery.soc > 0.5 and sim.battery.current > 0
    sim.undock()
    sim.run_goal(60)
    soc = sim.battery.soc
    sim.goto(37.6, 21.0, 0.0)
    sim.run_goal(300)
    s = sim.snapshot()
    assert s.battery_soc < soc and s.battery_current < 0
    assert 23.0 < s.battery_voltage < 26.0


def test_dock_and_undock():
    sim = Simulator(start="assembly_station", seed=0, lidar_enabled=False)
    sim.dock()
    assert sim.run_goal(300).status == "succeeded"
    assert sim.docked()
    with pytest.raises(GoalError, match="already docked"):
        sim.dock()
    sim.undock()
    assert sim.run_goal(60).status == "succeeded" and not sim.docked()


def test_conveyor_only_at_a_station():
    sim = Simulator(start="assembly_station", seed=0, lidar_enabled=False)
    with pytest.raises(GoalError, match="empty"):
        sim.conveyor_transfer(-1)
    sim.conveyor_transfer(+1)
    sim.step(2.0)
    mid = sim.snapshot()
    assert mid.conveyor_direction == 1 and mid.sensor_entry and mid.lamp == "yellow"
    sim.step(3.0)
    assert sim.snapshot().conveyor_loaded and sim.snapshot().sensor_seated
    sim.goto(20.0, 12.25, 0.0)
    with pytest.raises(GoalError, match="moving"):
        sim.conveyor_transfer(-1)
    sim.run_goal(200)
    with pytest.raises(GoalError, match="not at a conveyor station"):
        sim.conveyor_transfer(-1)


def test_same_seed_same_run():
    def run(seed):
        sim = Simulator(seed=seed)
        sim.add_obstacle("person", 6.0, 10.0)
        sim.goto(37.6, 21.0, 0.0)
        sim.step(40.0)
        s = sim.snapshot()
        return (s.x, s.y, s.theta, s.battery_soc), s.scan_ranges

    (a, sa), (b, sb) = run(5), run(5)
    assert a == b and np.array_equal(sa, sb)
    _, sc = run(6)
    assert not np.array_equal(sa, sc)


def test_grid_astar_fallback_finds_a_clear_path():
    sim = Simulator(seed=0, lidar_enabled=False)
    planner: PathPlanner = sim.path_planner
    plan = planner.plan((2.5, 3.0), (37.6, 21.0), method="grid")
    vis = planner.plan((2.5, 3.0), (37.6, 21.0), method="visibility")
    assert plan.method == "grid" and plan.waypoints[-1] == (37.6, 21.0)
    assert vis.length <= plan.length <= vis.length * 1.15
    # a goal fenced in by four pallets' worth of boxes has no path, by either method
    ring = [(33, 18, 35, 24), (40, 18, 42, 24), (33, 16, 42, 18), (33, 24, 42, 26)]
    for method in ("grid", "visibility"):
        with pytest.raises(PlanningError):
            planner.plan((2.5, 3.0), (37.6, 21.0), ring, method=method)


def test_a_differential_base_never_moves_sideways_and_reaches_its_goal():
    from astiop.sim.body import Body
    from astiop.sim.controller import ControllerGains
    from astiop.sim.kinematics import MecanumParams

    wheels = MecanumParams(lx=0.0, ly=0.08, wheel_radius=0.033, max_wheel_rpm=63.66)
    body = Body(0.14, 0.14, 1.0, wheels, differential=True)
    gains = ControllerGains(v_max=0.3, w_max=1.0, a_max=0.5, goal_tolerance=0.25)
    sim = Simulator(seed=0, start=(4.0, 4.0, 0.0), body=body, gains=gains)
    sim.goto(5.0, 6.0, math.pi / 2)  # behind and to the left: it must turn first
    top = 0.0
    while sim.goal is not None and sim.t < 120:
        sim.step(0.1)
        s = sim.snapshot()
        assert s.vy == 0.0
        top = max(top, s.vx)
    assert sim.last_result.status == "succeeded" and sim.last_result.error_m <= 0.25
    assert 0.2 < top <= 0.221  # the wheels' top speed, under the controller's 0.3
    sim.set_cmd_vel(0.1, 0.5, 0.0)  # a sideways command: only its forward part moves the base
    sim.step(0.3)
    assert sim.snapshot().vy == 0.0 and sim.snapshot().vx > 0.05

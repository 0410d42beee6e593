"""Goals for the base: checking, planning, the goto-pose control loop's targets, re-planning,
and whether it stands docked."""

from __future__ import annotations

import functools
import math
import threading
from collections.abc import Callable, Sequence

import numpy as np

from astiop.sim.base import Base, Pose, Teleop, Velocity
from astiop.sim.body import ASTIBOT_BODY
from astiop.sim.clock import Clock, SimEvents
from astiop.sim.controller import (
    ControllerGains,
    arrived,
    diff_drive_command,
    goto_pose_command,
    tracking_error,
)
from astiop.sim.geometry import segments_hit_boxes, wrap_angle
from astiop.sim.goal import Goal, GoalError, GoalResult, Leg
from astiop.sim.holds import Holds
from astiop.sim.path_planner import PathPlanner, PlanningError
from astiop.sim.perception import DetectedObstacle
from astiop.sim.scanner import Scanner
from astiop.sim.world import World
from astiop.warehouse import Station, WarehouseMap
from astiop.zones import MapZone, zone_at

ROBOT_LENGTH, ROBOT_WIDTH = ASTIBOT_BODY.length, ASTIBOT_BODY.width
INFLATION = ASTIBOT_BODY.inflation  # circumscribed radius + margin
BLOCKED_GIVE_UP_S = 60.0
# a speed zone is obeyed from this far ahead (and half a second at the commanded speed more),
# so the base has slowed down by the time it is inside
ZONE_AHEAD_M, ZONE_AHEAD_S = 0.3, 1.0
# Another robot of the fleet in the way: wait for it; plan around it every YIELD_REPLAN_S;
# give the goal up (and say so) after ROBOT_GIVE_UP_S. "In the way" is a robot seen within
# YIELD_GAP_M of the base's front, in its lane toward its next waypoint.
YIELD_GAP_M = 2.0  # two bases closing at full speed stop ~1.4 m apart from it
YIELD_LANE_MARGIN_M = 0.15  # each side of the base: robots docked side by side are 0.26 m apart
YIELD_REPLAN_S = 2.0
ROBOT_GIVE_UP_S = 30.0
ROBOT_BOX_PAD_M = 0.5  # a robot is seen from one side: its box grows this much each way


@functools.lru_cache(maxsize=8)
def _slow_gains(v_max: float) -> ControllerGains:
    """The gains of a slow leg (dock, undock): made once, not per control step."""
    return ControllerGains(v_max=v_max, w_max=0.3)


class Navigation:
    """The goal the base drives (one at a time, under `lock`) and how the last one ended; the
    map's keepout and speed zones it keeps to; the dock it charges at."""

    def __init__(
        self,
        *,
        lock: threading.RLock,
        warehouse: WarehouseMap,
        dock_name: str,
        world: World,
        planner: PathPlanner,
        base: Base,
        holds: Holds,
        scanner: Scanner,
        clock: Clock,
        events: SimEvents,
        gains: ControllerGains,
        blocked_give_up_s: float = BLOCKED_GIVE_UP_S,
    ) -> None:
        self.lock = lock
        self.map = warehouse
        self.dock_name = dock_name
        self.world = world
        self.planner = planner
        self.base = base
        self.holds = holds
        self.scanner = scanner
        self.clock = clock
        self.events = events
        self.gains = gains
        self.blocked_give_up_s = blocked_give_up_s  # a blocked goal is aborted after this
        self.goal: Goal | None = None
        self.plan: tuple[tuple[float, float], ...] = ()
        self.last_result: GoalResult | None = None
        self._goal_ids = 0
        self.plan_ms: list[float] = []
        # keepout and speed zones of the map, as plain geometry; `zone_source` (the store's,
        # handed by whoever runs the simulator) is read again at each goal
        self.zones: tuple[MapZone, ...] = ()
        self.zone_source: Callable[[], Sequence[MapZone]] | None = None
        self._dock: Station | None = warehouse.station(
            dock_name
        )  # looked up once: `docked()` is 20 Hz

    def set_zones(self, zones: Sequence[MapZone]) -> None:
        with self.lock:
            self.zones = tuple(zones)
            keepout = [z.corners for z in self.zones if z.kind == "keepout"]
            self.planner.set_keepout(keepout, self.base.chassis.inflation)

    def _take_zones(self) -> None:
        if self.zone_source is None:
            return
        try:
            zones = self.zone_source()
        except Exception:  # the source's own errors (a busy database): the last zones hold
            return
        self.set_zones(zones)

    def zone_speed(self, target: Velocity) -> Velocity:
        """A velocity within the limit of the speed zone the base is in or about to enter."""
        vx, vy, wz = target
        speed = math.hypot(vx, vy)
        if not self.zones or speed < 1e-6:
            return target
        x, y, theta = self.base.pose
        heading = theta + math.atan2(vy, vx)
        reach = ZONE_AHEAD_M + speed * ZONE_AHEAD_S
        ahead = (x + reach * math.cos(heading), y + reach * math.sin(heading))
        found = [zone_at(self.zones, x, y, "speed"), zone_at(self.zones, *ahead, "speed")]
        limit = min((z.speed for z in found if z is not None), default=math.inf)
        if speed <= limit:
            return target
        return (vx * limit / speed, vy * limit / speed, wz)

    def check_goal(self, x: float, y: float, theta: float) -> None:
        """Raise GoalError if the robot could never stand at this pose."""
        if not all(math.isfinite(v) for v in (x, y, theta)):
            raise GoalError("goal coordinates must be finite numbers")
        if not self.map.inside_bounds(x, y):
            x0, y0, x1, y1 = self.map.bounds
            raise GoalError(
                f"goal ({x:.2f}, {y:.2f}) is outside the map (x {x0:g}..{x1:g}, y {y0:g}..{y1:g} m)"
            )
        zone = zone_at(self.zones, x, y, "keepout")
        if zone is not None:
            raise GoalError(f"goal ({x:.2f}, {y:.2f}) is inside the {zone.words}")
        base = self.base.chassis
        hit = self.world.footprint_collides(x, y, theta, base.length, base.width, margin=0.05)
        if hit:
            raise GoalError(
                f"the robot does not fit at ({x:.2f}, {y:.2f}): it would overlap a "
                f"{hit.split(':')[0]}"
            )

    def _plan(self, start, goal_xy, extra=()) -> tuple[tuple[float, float], ...]:
        plan = self.planner.plan(start, goal_xy, extra)
        self.plan_ms.append(plan.ms)
        return plan.waypoints

    def goto(self, x: float, y: float, theta: float, name: str = "") -> Goal:
        self._take_zones()  # outside the lock: the source may wait on its database
        with self.lock:
            self.holds.check_can_move()
            self.check_goal(x, y, theta)
            px, py, _ = self.base.pose
            try:
                path = self._plan((px, py), (x, y))
            except PlanningError as exc:
                raise GoalError(f"no path to ({x:.2f}, {y:.2f}): {exc}") from None
            leg = Leg("navigate", (x, y, wrap_angle(theta)), list(path[1:]), self.gains.v_max)
            return self._start_goal(name or f"({x:.2f}, {y:.2f})", [leg])

    def dock(self) -> Goal:
        self._take_zones()
        with self.lock:
            self.holds.check_can_move()
            st = self.map.station(self.dock_name)
            if st is None or st.docked_pose is None:
                raise GoalError("this map has no charging dock")
            if self.docked():
                raise GoalError("the robot is already docked")
            legs = []
            ex, ey, _ = tracking_error(self.base.pose, st.pose)
            if math.hypot(ex, ey) > 0.05:
                try:
                    path = self._plan(self.base.pose[:2], st.pose[:2])
                except PlanningError as exc:
                    raise GoalError(f"no path to the dock: {exc}") from None
                legs.append(Leg("navigate", st.pose, list(path[1:]), self.gains.v_max))
            legs.append(Leg("dock", st.docked_pose, [st.docked_pose[:2]], 0.2, planned=False))
            return self._start_goal("dock", legs)

    def undock(self) -> Goal:
        with self.lock:
            self.holds.check_can_move()
            st = self.map.station(self.dock_name)
            if not self.docked() or st is None:
                raise GoalError("the robot is not docked")
            leg = Leg("undock", st.pose, [st.pose[:2]], 0.2, planned=False)
            return self._start_goal("undock", [leg])

    def _start_goal(self, name: str, legs: list[Leg]) -> Goal:
        if self.goal is not None:
            self.finish("canceled", f"replaced by a new goal: {name}")
        self.base.teleop = Teleop()
        self._goal_ids += 1
        self.goal = Goal(self._goal_ids, name, legs, self.clock.t)
        self._refresh_plan()
        self.events.say("goal", f"goal {self._goal_ids} accepted: {name}")
        return self.goal

    def _refresh_plan(self) -> None:
        g = self.goal
        self.plan = tuple(g.remaining_path(*self.base.pose[:2])) if g else ()

    def finish(self, status: str, message: str) -> None:
        g = self.goal
        if g is None:
            return
        ex, ey, _ = tracking_error(self.base.pose, g.final_pose)
        self.last_result = GoalResult(
            g.id, g.name, status, message, self.clock.t, math.hypot(ex, ey)
        )
        self.goal = None
        self.plan = ()
        self.base.target = (0.0, 0.0, 0.0)
        severity = "info" if status == "succeeded" else "warning"
        self.events.say("goal", f"goal {g.id} {status}: {message}", severity)

    def cancel(self, reason: str = "canceled by the operator") -> bool:
        with self.lock:
            had = self.goal is not None
            self.finish("canceled", reason)
            return had

    def docked(self) -> bool:
        dock = self._dock
        if dock is None or dock.docked_pose is None:
            return False
        pose = self.base.pose
        dx, dy, _ = dock.docked_pose
        if abs(dx - pose[0]) > 0.09 or abs(dy - pose[1]) > 0.09:
            return False  # surely more than 0.08 m off, the error below turned or not (20 Hz)
        ex, ey, eth = tracking_error(pose, dock.docked_pose)
        return math.hypot(ex, ey) < 0.08 and abs(eth) < math.radians(5) and self.base.speed() < 0.05

    # -- 20 Hz and 10 Hz, from the physics step ------------------------------------------------
    def navigate(self, g: Goal) -> Velocity:
        """The velocity the goto-pose control loop commands toward the goal `g` (the active one)
        this control step; it ends the goal where the base has arrived, or gives it up."""
        leg = g.current
        pose = self.base.pose
        if g.blocked_since is not None:
            return (0.0, 0.0, 0.0)
        # advance past waypoints already reached
        while (
            leg.waypoint < len(leg.path) - 1
            and math.dist(pose[:2], leg.path[leg.waypoint]) < self.gains.waypoint_radius
        ):
            leg.waypoint += 1
        if arrived(pose, leg.target, self.gains):
            if g.leg + 1 < len(g.legs):
                g.leg += 1
                self._refresh_plan()
                return (0.0, 0.0, 0.0)
            self.finish("succeeded", f"reached {g.name}")
            return (0.0, 0.0, 0.0)
        remaining = leg.remaining_length(pose[0], pose[1])
        if self._yield_to_robots(g, pose, remaining):
            return (0.0, 0.0, 0.0)
        leg = g.current  # a plan around a robot may have changed its path
        final = leg.waypoint == len(leg.path) - 1
        gains = self.gains if leg.v_max >= self.gains.v_max else _slow_gains(leg.v_max)
        remaining = leg.remaining_length(pose[0], pose[1])
        command = diff_drive_command if self.base.chassis.differential else goto_pose_command
        return command(pose, leg.path[leg.waypoint], leg.target[2], remaining, final, gains)

    def check_path(self, g: Goal) -> None:
        """After a scan: re-plan the goal `g` (the active one) around obstacles seen on its way,
        wait while there is no way round, and give it up after `blocked_give_up_s`."""
        if not g.current.planned:
            return
        x, y, _ = self.base.pose
        for ob in self.scanner.detected:
            if ob.kind != "robot" and ob.distance < 12.0:  # robots move: see _yield_to_robots
                bx0, by0, bx1, by1 = ob.bbox
                g.remember((bx0 - 0.15, by0 - 0.15, bx1 + 0.15, by1 + 0.15))
        if not g.known_boxes:
            return
        pts = np.array(g.remaining_path(x, y))
        boxes = np.array(g.known_boxes) + np.array([-1, -1, 1, 1]) * self.base.chassis.inflation
        cut = segments_hit_boxes(pts[:-1], pts[1:], boxes).any()
        if not cut and g.blocked_since is None:
            return
        leg = g.current
        try:
            path = self._plan((x, y), leg.target[:2], g.known_boxes)
        except PlanningError:
            if g.blocked_since is None:
                g.blocked_since = self.clock.t
                self.events.say("nav", f"path to {g.name} blocked; waiting", "warning")
            elif self.clock.t - g.blocked_since > self.blocked_give_up_s:
                self.finish("aborted", f"path blocked for {self.blocked_give_up_s:.0f} s")
            return
        if g.blocked_since is not None:
            self.events.say("nav", f"path to {g.name} clear again")
        g.blocked_since = None
        g.replans += 1
        leg.path, leg.waypoint = list(path[1:]), 0
        self._refresh_plan()

    # -- a fleet: other robots in the way ---------------------------------------------------
    def _robot_ahead(self, g: Goal, pose: Pose, remaining: float) -> DetectedObstacle | None:
        """The nearest robot seen in the base's way: in the lane as wide as the base (and a
        margin) ahead of it toward its next waypoint, up to its yield gap and not beyond where
        this leg ends."""
        detected = self.scanner.detected
        if not detected:
            return None  # nothing seen (20 Hz: spare the geometry below)
        leg = g.current
        wx, wy = leg.path[leg.waypoint] if leg.path else leg.target[:2]
        x, y, theta = pose
        if math.hypot(wx - x, wy - y) < 1e-3:
            return None
        heading = math.atan2(wy - y, wx - x)
        c, s = math.cos(heading), math.sin(heading)
        chassis = self.base.chassis
        reach = chassis.length / 2 + min(YIELD_GAP_M, remaining + 0.2)
        half = chassis.width / 2 + YIELD_LANE_MARGIN_M
        for ob in detected:  # nearest first
            if ob.distance > reach:
                break
            if ob.kind != "robot":
                continue
            near = (x + ob.distance * math.cos(theta + ob.bearing),
                    y + ob.distance * math.sin(theta + ob.bearing))  # fmt: skip
            x0, y0, x1, y1 = ob.bbox
            for px, py in (near, (x0, y0), (x0, y1), (x1, y0), (x1, y1)):
                along = (px - x) * c + (py - y) * s
                across = -(px - x) * s + (py - y) * c
                if 0.0 < along < reach and abs(across) < half:
                    return ob
        return None

    def _yield_to_robots(self, g: Goal, pose: Pose, remaining: float) -> bool:
        """Whether to hold still for another robot in the way this control step."""
        t = self.clock.t
        ahead = self._robot_ahead(g, pose, remaining)
        if ahead is None:
            if g.yielding_since is not None:
                g.yielding_since = None
                self.events.say("nav", f"path to {g.name} clear of robots again")
            return False
        if g.yielding_since is None:
            g.yielding_since = g.replanned_for_robot_t = t
            self.events.say("nav", f"waiting for a robot {ahead.distance:.1f} m ahead", "warning")
            return True
        if t - g.yielding_since > ROBOT_GIVE_UP_S:
            self.finish("aborted", f"another robot stayed in the way for {ROBOT_GIVE_UP_S:.0f} s")
            return True
        if self._gives_way_to(g, ahead.robot) and t - g.replanned_for_robot_t >= YIELD_REPLAN_S:
            g.replanned_for_robot_t = t
            if self._plan_around(g, ahead) and self._robot_ahead(g, pose, remaining) is None:
                self.events.say("nav", f"path to {g.name} planned around a robot in the way")
                return False
        return True

    def _gives_way_to(self, g: Goal, rank: int) -> bool:
        """The fleet's right of way: of two robots with goals, the one added to the world later
        plans around the other, which waits (two face to face never both turn back); a robot
        with no goal does not move, so it is planned around."""
        if not g.current.planned:
            return False
        other = self.world.robots[rank][3]
        return getattr(other, "goal", None) is None or rank < self.world.robot_rank(self.base.body)

    def _plan_around(self, g: Goal, robot: DetectedObstacle) -> bool:
        leg = g.current
        x0, y0, x1, y1 = robot.bbox
        pad = ROBOT_BOX_PAD_M
        box = (x0 - pad, y0 - pad, x1 + pad, y1 + pad)
        try:
            path = self._plan(self.base.pose[:2], leg.target[:2], [*g.known_boxes, box])
        except PlanningError:
            return False  # no way around: keep waiting
        g.replans += 1
        leg.path, leg.waypoint = list(path[1:]), 0
        self._refresh_plan()
        return True

"""Goals for the base: checking, planning, the goto-pose control loop's targets, re-planning.

A mixin of `Simulator`: it works on the simulator's world, path planner, pose and lock.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence

import numpy as np

from astiop.sim.body import ASTIBOT_BODY
from astiop.sim.controller import (
    ControllerGains,
    arrived,
    diff_drive_command,
    goto_pose_command,
    tracking_error,
)
from astiop.sim.geometry import segments_hit_boxes, wrap_angle
from astiop.sim.goal import Goal, GoalResult, Leg
from astiop.sim.path_planner import PlanningError
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


class GoalError(ValueError):
    """A goal or command was refused; the robot's state is unchanged."""


class NavigationMixin:
    # keepout and speed zones of the map, as plain geometry; `zone_source` (the store's, handed
    # by whoever runs the simulator) is read again at each goal
    zones: tuple[MapZone, ...] = ()
    zone_source: Callable[[], Sequence[MapZone]] | None = None

    def set_zones(self, zones: Sequence[MapZone]) -> None:
        with self.lock:
            self.zones = tuple(zones)
            keepout = [z.corners for z in self.zones if z.kind == "keepout"]
            self.path_planner.set_keepout(keepout, self.chassis.inflation)

    def _take_zones(self) -> None:
        if self.zone_source is None:
            return
        try:
            zones = self.zone_source()
        except Exception:  # the source's own errors (a busy database): the last zones hold
            return
        self.set_zones(zones)

    def _zone_speed(self, target: tuple[float, float, float]) -> tuple[float, float, float]:
        """A velocity within the limit of the speed zone the base is in or about to enter."""
        vx, vy, wz = target
        speed = math.hypot(vx, vy)
        if not self.zones or speed < 1e-6:
            return target
        x, y, theta = self.pose
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
        base = self.chassis
        hit = self.world.footprint_collides(x, y, theta, base.length, base.width, margin=0.05)
        if hit:
            raise GoalError(
                f"the robot does not fit at ({x:.2f}, {y:.2f}): it would overlap a "
                f"{hit.split(':')[0]}"
            )

    def _plan(self, start, goal_xy, extra=()) -> tuple[tuple[float, float], ...]:
        plan = self.path_planner.plan(start, goal_xy, extra)
        self.plan_ms.append(plan.ms)
        return plan.waypoints

    def goto(self, x: float, y: float, theta: float, name: str = "") -> Goal:
        self._take_zones()  # outside the lock: the source may wait on its database
        with self.lock:
            self._check_can_move()
            self.check_goal(x, y, theta)
            px, py, _ = self.pose
            try:
                path = self._plan((px, py), (x, y))
            except PlanningError as exc:
                raise GoalError(f"no path to ({x:.2f}, {y:.2f}): {exc}") from None
            leg = Leg("navigate", (x, y, wrap_angle(theta)), list(path[1:]), self.gains.v_max)
            return self._start_goal(name or f"({x:.2f}, {y:.2f})", [leg])

    def dock(self) -> Goal:
        self._take_zones()
        with self.lock:
            self._check_can_move()
            st = self.map.station(self.dock_name)
            if st is None or st.docked_pose is None:
                raise GoalError("this map has no charging dock")
            if self.docked():
                raise GoalError("the robot is already docked")
            legs = []
            ex, ey, _ = tracking_error(self.pose, st.pose)
            if math.hypot(ex, ey) > 0.05:
                try:
                    path = self._plan(self.pose[:2], st.pose[:2])
                except PlanningError as exc:
                    raise GoalError(f"no path to the dock: {exc}") from None
                legs.append(Leg("navigate", st.pose, list(path[1:]), self.gains.v_max))
            legs.append(Leg("dock", st.docked_pose, [st.docked_pose[:2]], 0.2, planned=False))
            return self._start_goal("dock", legs)

    def undock(self) -> Goal:
        with self.lock:
            self._check_can_move()
            st = self.map.station(self.dock_name)
            if not self.docked() or st is None:
                raise GoalError("the robot is not docked")
            leg = Leg("undock", st.pose, [st.pose[:2]], 0.2, planned=False)
            return self._start_goal("undock", [leg])

    def _start_goal(self, name: str, legs: list[Leg]) -> Goal:
        if self.goal is not None:
            self._finish("canceled", f"replaced by a new goal: {name}")
        self._clear_teleop()
        self._goal_ids += 1
        self.goal = Goal(self._goal_ids, name, legs, self.t)
        self._refresh_plan()
        self._event("goal", f"goal {self._goal_ids} accepted: {name}")
        return self.goal

    def _refresh_plan(self) -> None:
        g = self.goal
        self.plan = tuple(g.remaining_path(*self.pose[:2])) if g else ()

    def _finish(self, status: str, message: str) -> None:
        g = self.goal
        if g is None:
            return
        ex, ey, _ = tracking_error(self.pose, g.final_pose)
        self.last_result = GoalResult(g.id, g.name, status, message, self.t, math.hypot(ex, ey))
        self.goal = None
        self.plan = ()
        self._target = (0.0, 0.0, 0.0)
        severity = "info" if status == "succeeded" else "warning"
        self._event("goal", f"goal {g.id} {status}: {message}", severity)

    def cancel(self, reason: str = "canceled by the operator") -> bool:
        with self.lock:
            had = self.goal is not None
            self._finish("canceled", reason)
            return had

    def _navigate(self) -> tuple[float, float, float]:
        g = self.goal
        leg = g.current
        pose = self.pose
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
            self._finish("succeeded", f"reached {g.name}")
            return (0.0, 0.0, 0.0)
        remaining = leg.remaining_length(pose[0], pose[1])
        if self._yield_to_robots(pose, remaining):
            return (0.0, 0.0, 0.0)
        leg = g.current  # a plan around a robot may have changed its path
        final = leg.waypoint == len(leg.path) - 1
        gains = self.gains if leg.v_max >= self.gains.v_max else _slow_gains(leg.v_max)
        remaining = leg.remaining_length(pose[0], pose[1])
        command = diff_drive_command if self.chassis.differential else goto_pose_command
        return command(pose, leg.path[leg.waypoint], leg.target[2], remaining, final, gains)

    def _check_path(self) -> None:
        g = self.goal
        if not g.current.planned:
            return
        x, y, _ = self.pose
        for ob in self.detected:
            if ob.kind != "robot" and ob.distance < 12.0:  # robots move: see _yield_to_robots
                bx0, by0, bx1, by1 = ob.bbox
                g.remember((bx0 - 0.15, by0 - 0.15, bx1 + 0.15, by1 + 0.15))
        if not g.known_boxes:
            return
        pts = np.array(g.remaining_path(x, y))
        boxes = np.array(g.known_boxes) + np.array([-1, -1, 1, 1]) * self.chassis.inflation
        cut = segments_hit_boxes(pts[:-1], pts[1:], boxes).any()
        if not cut and g.blocked_since is None:
            return
        leg = g.current
        try:
            path = self._plan((x, y), leg.target[:2], g.known_boxes)
        except PlanningError:
            if g.blocked_since is None:
                g.blocked_since = self.t
                self._event("nav", f"path to {g.name} blocked; waiting", "warning")
            elif self.t - g.blocked_since > self.blocked_give_up_s:
                self._finish("aborted", f"path blocked for {self.blocked_give_up_s:.0f} s")
            return
        if g.blocked_since is not None:
            self._event("nav", f"path to {g.name} clear again")
        g.blocked_since = None
        g.replans += 1
        leg.path, leg.waypoint = list(path[1:]), 0
        self._refresh_plan()

    # -- a fleet: other robots in the way ---------------------------------------------------
    def _robot_ahead(self, pose, remaining: float):
        """The nearest robot seen in the base's way: in the lane as wide as the base (and a
        margin) ahead of it toward its next waypoint, up to its yield gap and not beyond where
        this leg ends."""
        if not self.detected:
            return None  # nothing seen (20 Hz: spare the geometry below)
        leg = self.goal.current
        wx, wy = leg.path[leg.waypoint] if leg.path else leg.target[:2]
        x, y, theta = pose
        if math.hypot(wx - x, wy - y) < 1e-3:
            return None
        heading = math.atan2(wy - y, wx - x)
        c, s = math.cos(heading), math.sin(heading)
        reach = self.chassis.length / 2 + min(YIELD_GAP_M, remaining + 0.2)
        half = self.chassis.width / 2 + YIELD_LANE_MARGIN_M
        for ob in self.detected:  # nearest first
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

    def _yield_to_robots(self, pose, remaining: float) -> bool:
        """Whether to hold still for another robot in the way this control step."""
        g = self.goal
        ahead = self._robot_ahead(pose, remaining)
        if ahead is None:
            if g.yielding_since is not None:
                g.yielding_since = None
                self._event("nav", f"path to {g.name} clear of robots again")
            return False
        if g.yielding_since is None:
            g.yielding_since = g.replanned_for_robot_t = self.t
            self._event("nav", f"waiting for a robot {ahead.distance:.1f} m ahead", "warning")
            return True
        if self.t - g.yielding_since > ROBOT_GIVE_UP_S:
            self._finish("aborted", f"another robot stayed in the way for {ROBOT_GIVE_UP_S:.0f} s")
            return True
        if self._gives_way_to(ahead.robot) and self.t - g.replanned_for_robot_t >= YIELD_REPLAN_S:
            g.replanned_for_robot_t = self.t
            if self._plan_around(ahead) and self._robot_ahead(pose, remaining) is None:
                self._event("nav", f"path to {g.name} planned around a robot in the way")
                return False
        return True

    def _gives_way_to(self, rank: int) -> bool:
        """The fleet's right of way: of two robots with goals, the one added to the world later
        plans around the other, which waits (two face to face never both turn back); a robot
        with no goal does not move, so it is planned around."""
        if not self.goal.current.planned:
            return False
        other = self.world.robots[rank][3]
        return getattr(other, "goal", None) is None or rank < self.world.robot_rank(self.body)

    def _plan_around(self, robot) -> bool:
        g, leg = self.goal, self.goal.current
        x0, y0, x1, y1 = robot.bbox
        pad = ROBOT_BOX_PAD_M
        box = (x0 - pad, y0 - pad, x1 + pad, y1 + pad)
        try:
            path = self._plan(self.pose[:2], leg.target[:2], [*g.known_boxes, box])
        except PlanningError:
            return False  # no way around: keep waiting
        g.replans += 1
        leg.path, leg.waypoint = list(path[1:]), 0
        self._refresh_plan()
        return True

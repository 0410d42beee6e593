"""Safety in code, on by default: speed limits, a geofence, the e-stop, confirmation."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from astiop.ros2.command import Ros2Command
from astiop.ros2.render import POSE_STAMPED  # a goal on a navigator's goal topic
from astiop.ros2.validation import Checked, always_allowed
from astiop.warehouse import GEOFENCE_MARGIN, fence_text, inside_fence
from astiop.zones import MapZone, zone_at

# A velocity command is clamped by its type, whatever the topic (a namespace's /tb3_1/cmd_vel)
VELOCITY_TYPES = {"geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"}
POSE_WITH_COVARIANCE = "geometry_msgs/msg/PoseWithCovarianceStamped"
# |q| may differ from 1 by this much (a heading printed to a few digits still passes)
UNIT_QUATERNION_TOLERANCE = 1e-3
# Teleop toward a keepout zone is refused when the point this far ahead of the robot's centre
# (its half length and a margin, plus half a second at the commanded speed) is inside it
ZONE_LOOKAHEAD_M, ZONE_LOOKAHEAD_S = 0.45, 0.5


@dataclass(frozen=True)
class Review:
    allowed: bool
    reason: str
    checked: Checked  # possibly with clamped values and notes
    needs_confirmation: bool


def releases_a_stop(checked: Checked, release: str | None = None) -> bool:
    """A call that lets a held robot go: a release service under any namespace (`release`:
    the robot's own name for it, from its profile)."""
    cmd = checked.command
    if cmd is None or cmd.key != ("service", "call"):
        return False
    name = (cmd.name or "").rstrip("/")
    return name.rsplit("/", 1)[-1] == "release" or (bool(release) and name == release)


@dataclass
class SafetyPolicy:
    max_linear: float = 0.8
    max_angular: float = 1.0
    # make_safety gives the profile's [map] geofence, else None until the robot's map is read
    # (RobotGateway.use_map): None refuses every goal; the default is the warehouse's
    geofence: tuple[float, float, float, float] | None = (0.0, 0.0, 40.0, 25.0)
    geofence_margin: float = GEOFENCE_MARGIN
    confirm_actuation: bool = True
    # where a named location is (x, y), so a goal by name is fenced like one by coordinates
    locate: Callable[[str], tuple[float, float] | None] | None = None
    # the zones of the robot's map (the store's), read at each review; where the robot is
    # (x, y, theta), read only for a velocity command while there are zones
    zones: Callable[[], list[MapZone]] | None = None
    where: Callable[[], tuple[float, float, float] | None] | None = None

    def adopt_robot_limit(self, cmd: Ros2Command, message: dict[str, Any] | None) -> None:
        """A `param set` of the robot's own speed limit that went through becomes this clamp
        too (the robot's limit is the one it enforces; safety must not allow more)."""
        if cmd.key != ("param", "set") or message is None:
            return
        if cmd.args["param"] == "max_linear_speed":
            self.max_linear = message["value"]
        elif cmd.args["param"] == "max_angular_speed":
            self.max_angular = message["value"]

    def _zones(self) -> list[MapZone]:
        return self.zones() if self.zones is not None else []

    def keepout_at(self, x: float, y: float) -> MapZone | None:
        return zone_at(self._zones(), x, y, "keepout")

    def _zone_reason(self, x: float, y: float) -> str:
        zone = self.keepout_at(x, y)
        return f"goal ({x:.2f}, {y:.2f}) is inside the {zone.words}" if zone else ""

    def inside_geofence(self, x: float, y: float) -> bool:
        if self.geofence is None:
            return False
        return inside_fence(self.geofence, x, y, self.geofence_margin)

    def _fence_reason(self, x: float, y: float) -> str:
        if self.geofence is None:
            return (
                f"goal ({x:.2f}, {y:.2f}) refused: no geofence is known for this robot (no /map "
                "read yet, and no [map] geofence in its profile)"
            )
        fence = fence_text(self.geofence, self.geofence_margin)
        return f"goal ({x:.2f}, {y:.2f}) is outside the geofence ({fence})"

    def review(self, checked: Checked, e_stopped: bool) -> Review:
        if not checked.valid or checked.kind != "actuate":
            return Review(checked.valid, checked.reason, checked, False)
        cmd = checked.command
        assert cmd is not None  # valid, so parsed
        name = cmd.name or ""
        base = name.rsplit("/", 1)[-1]
        if always_allowed(checked):
            return Review(True, "", checked, False)
        if e_stopped:
            return Review(
                False,
                "the E-STOP is engaged: no motion command runs until the operator releases it",
                checked,
                False,
            )
        msg = checked.message or {}
        notes: list[str] = list(checked.notes)
        velocity = cmd.key == ("topic", "pub") and checked.type in VELOCITY_TYPES
        if velocity and "twist" in msg:
            twist, notes = self._clamp_twist(msg["twist"], notes)  # TwistStamped: same clamp
            msg = {**msg, "twist": twist}
        elif velocity:
            msg, notes = self._clamp_twist(msg, notes)
        if velocity:
            twist = msg.get("twist", msg)
            twist, notes, why = self._zone_twist(twist, notes)
            if why:
                return Review(False, why, checked, False)
            msg = {**msg, "twist": twist} if "twist" in msg else twist
        elif cmd.key == ("service", "call") and base == "goto_position":
            where = self.locate(msg["name"]) if msg.get("name") and self.locate else None
            x, y = where if where else (msg.get("x", 0.0), msg.get("y", 0.0))
            if where or not msg.get("name"):
                inside = self.inside_geofence(x, y)
                why = self._zone_reason(x, y) if inside else self._fence_reason(x, y)
                if why:
                    label = f"'{msg['name']}' at " if where else ""
                    return Review(False, label + why, checked, False)
        elif cmd.key == ("action", "send_goal") or (
            cmd.key == ("topic", "pub") and checked.type == POSE_STAMPED  # a /goal_pose
        ):
            why = self._goal_refusal(msg["pose"] if cmd.key[0] == "action" else msg)
            if why:
                return Review(False, why, checked, False)
        elif cmd.key == ("topic", "pub") and checked.type == POSE_WITH_COVARIANCE:
            # where the robot is told it is (amcl's /initialpose): on the map, inside the fence
            why = self._goal_refusal({"header": msg["header"], "pose": msg["pose"]["pose"]})
            if why:
                return Review(False, why.replace("goal", "pose"), checked, False)
        elif cmd.key == ("param", "set") and cmd.args.get("param") in (
            "max_linear_speed",
            "max_angular_speed",
        ):
            limit = 1.4 if cmd.args["param"] == "max_linear_speed" else 3.0
            if msg["value"] > limit:
                return Review(False, f"{cmd.args['param']} may not exceed {limit}", checked, False)
        out = replace(checked, message=msg, notes=tuple(notes))
        return Review(True, "", out, self.confirm_actuation)

    def _goal_refusal(self, pose: dict) -> str:
        """Why a goal pose (a PoseStamped) may not be sent: "" when it may."""
        frame = pose["header"]["frame_id"]
        if frame not in ("", "map"):
            return f"goals must be in the map frame, not '{frame}'"
        p = pose["pose"]["position"]
        if not self.inside_geofence(p["x"], p["y"]):
            return self._fence_reason(p["x"], p["y"])
        if why := self._zone_reason(p["x"], p["y"]):
            return why
        q = pose["pose"]["orientation"]
        norm = math.hypot(q["x"], q["y"], q["z"], q["w"])  # hypot: no overflow at 1e308
        if not abs(norm - 1.0) <= UNIT_QUATERNION_TOLERANCE:
            return (
                f"the goal's orientation is not a unit quaternion (|q| = {norm:.6g}); "
                "for a heading θ use {z: sin(θ/2), w: cos(θ/2)}"
            )
        return ""

    def _zone_twist(self, twist: dict, notes: list[str]) -> tuple[dict, list[str], str]:
        """A velocity within the speed zone the robot is in or about to enter, and why it may
        not be sent: it would drive the robot into a keepout zone (turning stays allowed, and
        so does leaving one the robot is inside)."""
        zones = self._zones()
        pose = self.where() if zones and self.where is not None else None
        if pose is None:
            return twist, notes, ""
        x, y, theta = pose
        vx, vy = twist["linear"]["x"], twist["linear"]["y"]
        speed = math.hypot(vx, vy)
        ahead = (x, y)
        if speed > 1e-6:
            heading = theta + math.atan2(vy, vx)
            reach = ZONE_LOOKAHEAD_M + speed * ZONE_LOOKAHEAD_S
            ahead = (x + reach * math.cos(heading), y + reach * math.sin(heading))
            into = zone_at(zones, *ahead, "keepout")
            if into is not None and not into.contains(x, y):
                return twist, notes, f"teleop refused: that way the robot enters the {into.words}"
        around = (zone_at(zones, x, y, "speed"), zone_at(zones, *ahead, "speed"))
        # a speed zone always has its limit (zones.check_zone)
        slow = [(z.speed, z) for z in around if z is not None and z.speed is not None]
        if slow and speed > (limit := min(zone_speed for zone_speed, _ in slow)):
            zone = min(slow, key=lambda pair: pair[0])[1]
            s = limit / speed
            lin = {**twist["linear"], "x": vx * s, "y": vy * s}
            twist = {**twist, "linear": lin}
            notes = [*notes, f"linear speed clamped {speed:.2f} -> {limit:.2f} m/s in the "
                     f"{zone.words}"]  # fmt: skip
        return twist, notes, ""

    def _clamp_twist(self, msg: dict, notes: list[str]) -> tuple[dict, list[str]]:
        twist, more = clamp_twist(msg, self.max_linear, self.max_angular)
        return twist, notes + more


def clamp_twist(msg: dict, max_linear: float, max_angular: float) -> tuple[dict, list[str]]:
    """A ground robot's velocity within its limits: planar speed scaled down as a whole (the
    direction kept), the turn rate clipped; returns what was changed, in words."""
    notes: list[str] = []
    lin, ang = dict(msg["linear"]), dict(msg["angular"])
    if lin["z"] or ang["x"] or ang["y"]:
        notes.append("a ground robot ignores linear.z, angular.x and angular.y: set to 0")
        lin["z"] = ang["x"] = ang["y"] = 0.0
    speed = math.hypot(lin["x"], lin["y"])
    if speed > max_linear:
        s = max_linear / speed
        notes.append(f"linear speed clamped {speed:.2f} -> {max_linear:.2f} m/s")
        lin["x"], lin["y"] = lin["x"] * s, lin["y"] * s
    if abs(ang["z"]) > max_angular:
        notes.append(f"angular speed clamped {abs(ang['z']):.2f} -> {max_angular:.2f} rad/s")
        ang["z"] = math.copysign(max_angular, ang["z"])
    return {"linear": lin, "angular": ang}, notes
